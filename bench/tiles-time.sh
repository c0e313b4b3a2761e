#!/usr/bin/env bash
# `cota tiles` end to end, this build against another cota binary (e.g. one
# built from an earlier commit), interleaved in one loop so that both see the
# same machine load. Medians of the process's wall time and of the report's
# prepare and tiles phases (from --json), per input and binary.
#
# Usage: bench/tiles-time.sh OTHER_COTA [RUNS]
#   OTHER_COTA  the binary to compare with (required)
#   RUNS        runs per input and binary (default 7)
# Inputs: the bundled fixture S29W072 (the README's tiles command) and the
# two adjacent tiles N00E010 + N00E011 of ../shared/data, default options
# (max zoom from the data), written into a scratch folder.
set -u
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
other="${1:?usage: bench/tiles-time.sh OTHER_COTA [RUNS]}"
runs="${2:-7}"
data="${COTA_SHARED_DATA:-$root/../shared/data}"
(cd "$root" && cargo build --release -q -p cota-cli --bin cota) || exit 1
scratch="$(mktemp -d "$root/target/tiles-time.XXXXXX")"
trap 'rm -rf "$scratch"' EXIT
inputs=("fixture|")
[ -f "$data/srtm/N00E010.hgt" ] && [ -f "$data/srtm/N00E011.hgt.zip" ] &&
  inputs+=("mosaic2|$data/srtm/N00E010.hgt $data/srtm/N00E011.hgt.zip")
echo "cota tiles, $runs runs each, interleaved, $(nproc) cores; load $(cut -d' ' -f1-3 /proc/loadavg)"
python3 - "$scratch" "$runs" "$root/target/release/cota" "$other" "${inputs[@]}" <<'PY'
import json, os, shutil, statistics as st, subprocess, sys, time
scratch, runs, this, other, *inputs = sys.argv[1:]
bins = {"this": this, "other": other}
rows = []
for spec in inputs:
    name, args = spec.split("|", 1)
    times = {b: {"wall": [], "prepare": [], "tiles": []} for b in bins}
    count = {}
    for r in range(int(runs)):
        for b, exe in bins.items():
            out = os.path.join(scratch, f"{name}-{b}")
            shutil.rmtree(out, ignore_errors=True)
            t = time.perf_counter()
            p = subprocess.run([exe, "tiles", *args.split(), "-o", out, "--json"],
                               capture_output=True, text=True)
            wall = time.perf_counter() - t
            if p.returncode != 0:
                sys.exit(f"{b} on {name}: {p.stderr}")
            v = json.loads(p.stdout)
            times[b]["wall"].append(wall)
            tm = v.get("seconds", {})
            times[b]["prepare"].append(tm.get("prepare", float("nan")))
            times[b]["tiles"].append(tm.get("tiles", float("nan")))
            count[b] = v.get("tiles")
    med = {b: {k: st.median(x) for k, x in t.items()} for b, t in times.items()}
    for b in bins:
        m = med[b]
        rows.append(f"| {name} | {b} | {count[b]} | {m['prepare']:.3f} | {m['tiles']:.3f} | {m['wall']:.3f} | "
                    f"{m['wall'] / med['other']['wall']:.2f}× |")
print("| input | binary | tiles | prepare (s) | tiles (s) | wall (s) | wall ÷ other |")
print("|---|---|---:|---:|---:|---:|---:|")
print("\n".join(rows))
PY
