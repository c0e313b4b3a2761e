#!/usr/bin/env bash
# Peak resident memory of `cota mesh` on the large grids (srtm3601, mosaic8;
# see crates/cota-bench/src/big.rs), under GNU time's `-v`, as bytes per
# sample against the target of 8 B/sample (1.5 × the grid's f32 size + 2 B per
# sample for the hierarchy). The counting-allocator figures per phase come
# from `cargo run --release -p cota-bench --bin memory`.
#
# Usage: bench/memory.sh [E...]   (default E: 1 5 20; no output file is written,
#        so the figures are read + mosaic + fill + build + extract + report)
# Needs /usr/bin/time (Debian package `time`: apt-get install time); without it
# the script says so and exits 0.
set -u
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
es=("$@")
[ ${#es[@]} -eq 0 ] && es=(1 5 20)
if [ ! -x /usr/bin/time ] || ! /usr/bin/time -v true >/dev/null 2>&1; then
  echo "memory.sh: GNU time (/usr/bin/time -v) not found; install it with 'apt-get install time'" >&2
  exit 0
fi
(cd "$root" && cargo build --release -q -p cota-cli --bin cota && cargo build --release -q -p cota-bench --bin export-grid) || exit 1
cota="$root/target/release/cota"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
"$root/target/release/export-grid" big-tiles "$scratch" >"$scratch/list.txt" || exit 1

echo "cota mesh under /usr/bin/time -v; load $(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null)"
echo
echo "| grid | samples | E (m) | triangles | max RSS MB | RSS B/sample | ÷ target (8 B/sample) | wall s |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|"
while read -r name files; do
  [ "$name" = big4097 ] && continue
  # shellcheck disable=SC2086
  set -- $files
  for e in "${es[@]}"; do
    /usr/bin/time -v -o "$scratch/time.txt" "$cota" mesh "$@" --max-error "$e" --json >"$scratch/out.json" 2>"$scratch/err.txt" \
      || { echo "memory.sh: cota mesh failed on $name at E=$e:" >&2; cat "$scratch/err.txt" >&2; continue; }
    rss_kb=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$scratch/time.txt")
    wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$scratch/time.txt")
    python3 - "$scratch/out.json" "$name" "$e" "$rss_kb" "$wall" <<'PY'
import json, sys
path, name, e, rss_kb, wall = sys.argv[1:]
j = json.load(open(path))
def find(d, keys):
    # First value under any of `keys`, searching nested objects.
    if isinstance(d, dict):
        for k in keys:
            if k in d and not isinstance(d[k], (dict, list)):
                return d[k]
        for v in d.values():
            r = find(v, keys)
            if r is not None:
                return r
    return None
w, h = find(j, ["width"]), find(j, ["height"])
tris = find(j, ["triangles", "triangle_count"])
n = int(w) * int(h)
rss = int(rss_kb) * 1024
m, s = wall.split(":")[-2:]
print(f"| {name} {w}×{h} | {n:,} | {e} | {tris:,} | {rss / 2**20:.1f} | {rss / n:.2f} | {rss / (8 * n):.2f} | {float(m) * 60 + float(s):.1f} |")
PY
  done
done <"$scratch/list.txt"
