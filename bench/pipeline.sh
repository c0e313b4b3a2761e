#!/usr/bin/env bash
# End to end: `cota mesh` with the default report, per stage (from its
# `--json`: read, build, extract, measure, write, total) and the wall time of
# the whole process, against the engine's own time (read + build + extract).
# The issue's target: wall ≤ 1.5 × (read + build + extract).
#
# Usage: bench/pipeline.sh [RUNS] [OTHER_COTA]
#   RUNS        runs per input and binary (default 5); the table gives medians.
#   OTHER_COTA  a second cota binary (e.g. one built from `main`): both are run
#               in turn, in the same loop, and their outputs must be identical
#               byte for byte (the script exits 1 otherwise).
# Inputs: the README's command (the bundled S29W072 tile, E = 5 m) and the two
# adjacent tiles N00E010 + N00E011 of ../shared/data at E = 5 m, each written as
# a GLB into a scratch folder (on the same disk as the repository, so `fsync`
# is part of the write as in real use).
set -u
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
runs="${1:-5}"
other="${2:-}"
data="${COTA_SHARED_DATA:-$root/../shared/data}"
(cd "$root" && cargo build --release -q -p cota-cli --bin cota) || exit 1
scratch="$(mktemp -d "$root/target/pipeline.XXXXXX")"
trap 'rm -rf "$scratch"' EXIT

bins=("this=$root/target/release/cota")
[ -n "$other" ] && bins+=("other=$other")
inputs=("readme|--max-error 5")
if [ -f "$data/srtm/N00E010.hgt" ] && [ -f "$data/srtm/N00E011.hgt.zip" ]; then
  inputs+=("mosaic2|$data/srtm/N00E010.hgt $data/srtm/N00E011.hgt.zip --max-error 5")
else
  echo "pipeline.sh: $data/srtm/N00E01{0,1} not found: mosaic2 skipped" >&2
fi

echo "cota mesh, $runs runs each, $(nproc) cores; load $(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null)"
for spec in "${inputs[@]}"; do
  name="${spec%%|*}"
  # shellcheck disable=SC2206
  args=(${spec#*|})
  for r in $(seq "$runs"); do
    for b in "${bins[@]}"; do
      label="${b%%=*}"
      out="$scratch/$name-$label.glb"
      t0=$(date +%s%N)
      "${b#*=}" mesh "${args[@]}" -o "$out" --json >"$scratch/$name-$label-$r.json" \
        || { echo "pipeline.sh: $label failed on $name" >&2; exit 1; }
      t1=$(date +%s%N)
      echo "$(( (t1 - t0) / 1000 ))" >"$scratch/$name-$label-$r.wall"
    done
    if [ -n "$other" ] && ! cmp -s "$scratch/$name-this.glb" "$scratch/$name-other.glb"; then
      echo "pipeline.sh: $name: the two binaries wrote different bytes" >&2
      exit 1
    fi
  done
done
[ -n "$other" ] && echo "outputs identical byte for byte (this vs other, every run)"

python3 - "$scratch" "$runs" "${bins[@]}" <<'PY'
import json, os, statistics, sys
scratch, runs, bins = sys.argv[1], int(sys.argv[2]), [b.split("=")[0] for b in sys.argv[3:]]
names = sorted({f.split("-")[0] for f in os.listdir(scratch) if f.endswith(".json")}, reverse=True)
stages = ["read_ms", "build_ms", "extract_ms", "measure_ms", "write_ms", "total_ms"]
print()
print("| input | binary | triangles | GLB MB | read | build | extract | measure | write | total (cota) | wall (process) | wall ÷ (read+build+extract) |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for n in names:
    for b in bins:
        reps = []
        for r in range(1, runs + 1):
            d = json.load(open(f"{scratch}/{n}-{b}-{r}.json"))
            d["wall_ms"] = int(open(f"{scratch}/{n}-{b}-{r}.wall").read()) / 1e3
            reps.append(d)
        med = {k: statistics.median(d.get(k) or 0.0 for d in reps) for k in stages + ["wall_ms"]}
        ratio = statistics.median(d["wall_ms"] / (d["read_ms"] + d["build_ms"] + d["extract_ms"]) for d in reps)
        mb = os.path.getsize(f"{scratch}/{n}-{b}.glb") / 1e6
        total = f"{med['total_ms']:.0f}" if med["total_ms"] else "-"
        print(f"| {n} | {b} | {reps[0]['triangles']} | {mb:.1f} | " + " | ".join(f"{med[k]:.0f}" for k in stages[:5])
              + f" | {total} | {med['wall_ms']:.0f} | {ratio:.2f}× |")
print()
print("Times in ms, medians; the ratio is the median of the per-run ratios.")
PY
