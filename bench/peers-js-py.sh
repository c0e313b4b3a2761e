#!/usr/bin/env bash
# The JS and Python peers on cota's benchmark grids: @mapbox/martini and
# delatin (npm) and pydelatin (PyPI), installed into bench/.peers (ignored by
# git, never committed). Prints a markdown table of times per grid and error.
#
# Usage: bench/peers-js-py.sh [GRID...]   (default: fuji513 puget1025 srtm1025 srtm1201)
# Env:   COTA_PEERS_DIR (install dir, default bench/.peers),
#        COTA_PEERS_E (tolerances, default 0.5,1,2,5,10,20,50),
#        COTA_PEERS_DELATIN_MIN_E (skip both delatins below it, default 5).
# Degrades gracefully: without node/npm, pip or the network, it says what is
# missing, skips that peer, and exits 0.
set -u
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
peers="${COTA_PEERS_DIR:-$here/.peers}"
es="${COTA_PEERS_E:-0.5,1,2,5,10,20,50}"
dmin="${COTA_PEERS_DELATIN_MIN_E:-5}"
grids=("$@")
[ ${#grids[@]} -eq 0 ] && grids=(fuji513 puget1025 srtm1025 srtm1201)
mkdir -p "$peers/grids"
export COTA_PEERS_DIR="$peers"

have_js=0
if command -v node >/dev/null && command -v npm >/dev/null; then
  if [ -d "$peers/node_modules/@mapbox/martini" ] && [ -d "$peers/node_modules/delatin" ]; then
    have_js=1
  else
    [ -f "$peers/package.json" ] || echo '{"private": true}' > "$peers/package.json"
    if npm install --prefix "$peers" --no-audit --no-fund --silent @mapbox/martini@0.2.0 delatin@0.2.0 >"$peers/npm.log" 2>&1; then
      have_js=1
    else
      echo "peers-js-py: npm install failed (no network?), skipping the JS peers; see $peers/npm.log" >&2
    fi
  fi
else
  echo "peers-js-py: node or npm not found, skipping @mapbox/martini and delatin (npm)" >&2
fi

have_py=0
py="$(command -v python3 || true)"
if [ -n "$py" ] && "$py" -m pip --version >/dev/null 2>&1; then
  if PYTHONPATH="$peers/py" "$py" -c 'import pydelatin, numpy' >/dev/null 2>&1; then
    have_py=1
  elif "$py" -m pip install --quiet --disable-pip-version-check --target "$peers/py" pydelatin==0.4.0 numpy >"$peers/pip.log" 2>&1 \
      && PYTHONPATH="$peers/py" "$py" -c 'import pydelatin, numpy' >/dev/null 2>&1; then
    have_py=1
  else
    echo "peers-js-py: pip install of pydelatin failed (no network or no wheel?), skipping it; see $peers/pip.log" >&2
  fi
else
  echo "peers-js-py: python3 with pip not found, skipping pydelatin" >&2
fi

if [ $have_js -eq 0 ] && [ $have_py -eq 0 ]; then
  echo "peers-js-py: no peer available; nothing to do" >&2
  exit 0
fi

if ! (cd "$root" && cargo build --release -q -p cota-bench --bin export-grid); then
  echo "peers-js-py: could not build export-grid" >&2
  exit 0
fi
export_grid="$root/target/release/export-grid"

results="$peers/results.tsv"
: > "$results"
for g in "${grids[@]}"; do
  f="$peers/grids/$g.f32"
  dims="$("$export_grid" raw "$g" "$f")" || { echo "peers-js-py: skipping $g" >&2; continue; }
  read -r _ w h <<<"$dims"
  echo "peers-js-py: $g ${w}x${h}" >&2
  if [ $have_js -eq 1 ]; then
    node "$here/peers/martini_delatin.mjs" "$f" "$w" "$h" "$g" "$es" "$dmin" >>"$results" \
      || echo "peers-js-py: the JS peers failed on $g" >&2
  fi
  if [ $have_py -eq 1 ]; then
    PYTHONPATH="$peers/py" "$py" "$here/peers/pydelatin_bench.py" "$f" "$w" "$h" "$g" "$es" "$dmin" >>"$results" \
      || echo "peers-js-py: pydelatin failed on $g" >&2
  fi
done

echo "node $(node --version 2>/dev/null || echo -), python $("$py" --version 2>&1 | cut -d' ' -f2), load $(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null)"
echo
echo "| grid | tool | step | E (m) | median ms | min ms | runs | triangles |"
echo "|---|---|---|---:|---:|---:|---:|---:|"
awk -F'\t' '{ printf "| %s | %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6, $7, $8 }' "$results"
exit 0
