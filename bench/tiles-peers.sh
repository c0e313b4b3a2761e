#!/usr/bin/env bash
# cota tiles against the Python per-tile quantized-mesh pipeline (pymartini or
# pydelatin + quantized-mesh-encoder, as dem-tiler does), on the same lattice,
# tiles and zooms; every pyramid measured by cota's decoder and checker.
# Usage: bench/tiles-peers.sh [FILE...] (default: ../shared/data/srtm N00E010 + N00E011)
set -euo pipefail
cd "$(dirname "$0")/.."
P=bench/.peers
FILES=("$@")
[ ${#FILES[@]} -gt 0 ] || FILES=(../shared/data/srtm/N00E010.hgt ../shared/data/srtm/N00E011.hgt.zip)
cargo build --release -q -p cota-cli -p cota-bench --bin cota --bin tiles-peers
if [ ! -x $P/tiles-venv/bin/python ]; then
  python3 -m venv $P/tiles-venv
  $P/tiles-venv/bin/pip install -q numpy==2.2.6 pymartini==0.6.0 pydelatin==0.4.0 quantized-mesh-encoder==0.5.0
fi
$P/tiles-venv/bin/pip install -q alcesium-terrain-maker 2>/dev/null || echo "alcesium-terrain-maker: does not install here (no distribution for this Python/platform)"
./target/release/tiles-peers export $P/lattice "${FILES[@]}"
run() { # name, command...
  local name=$1; shift
  rm -rf "$P/$name"
  local t0=$(date +%s.%N)
  "$@" > /dev/null 2>&1
  local t1=$(date +%s.%N)
  printf '%s\t%.2f\t%s\n' "$name" "$(echo "$t1 - $t0" | bc)" "$(./target/release/tiles-peers measure "$P/$name" "${FILES[@]}")"
}
for rep in 1 2 3; do
  run cota ./target/release/cota tiles -o $P/cota "${FILES[@]}"
  run martini-1.0 $P/tiles-venv/bin/python bench/tiles_peers.py $P/lattice $P/martini-1.0 martini 1.0 2
done
for f in 0.5 0.45 0.4; do
  run martini-$f $P/tiles-venv/bin/python bench/tiles_peers.py $P/lattice $P/martini-$f martini $f 2
done
run delatin-1.0 $P/tiles-venv/bin/python bench/tiles_peers.py $P/lattice $P/delatin-1.0 delatin 1.0 2
