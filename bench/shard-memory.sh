#!/usr/bin/env bash
# Peak resident memory (GNU time -v, "Maximum resident set size") of a plain
# `cota tiles` against the plan step, each shard and the reduce of a sharded
# run over parts of the lattice (issue 20), for N = 2 and 4, on
#   mosaic2: ../shared/data/srtm/N00E010.hgt + N00E011.hgt.zip (1201² each);
#   mosaic8: a relabelled 4×2 block of copies of those two void-free tiles
#            (N10E020..N10E023, N09E020..N09E023; real samples at false
#            positions, seams between copies disagree and are averaged).
# Each pyramid is checked byte-identical to the plain run (diff -r).
# usage: bench/shard-memory.sh [COTA] [--max-zoom Z ...extra tiles args]
set -eu
here="$(cd "$(dirname "$0")" && pwd)"
data="${COTA_SHARED_DATA:-$here/../../shared/data}"
cota="${1:-$here/../target/release/cota}"
shift || true
extra=("$@")
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/m8"
cp "$data/srtm/N00E010.hgt" "$tmp/a.hgt"
python3 - "$data/srtm/N00E011.hgt.zip" "$tmp/b.hgt" <<'PY'
import sys, zipfile
z = zipfile.ZipFile(sys.argv[1])
open(sys.argv[2], "wb").write(z.read(z.namelist()[0]))
PY
m8=()
for lat in 10 9; do
  for lon in 20 21 22 23; do
    src=a; [ $(((lon + lat) % 2)) -eq 1 ] && src=b
    f="$tmp/m8/N$(printf %02d $lat)E$(printf %03d $lon).hgt"
    cp "$tmp/$src.hgt" "$f"
    m8+=("$f")
  done
done
rss() { # label, then the command: prints "label | MB"
  local label="$1"; shift
  /usr/bin/time -v "$@" >/dev/null 2>"$tmp/time" || { cat "$tmp/time" >&2; exit 1; }
  awk -v l="$label" '/Maximum resident set size/ {printf "%s | %.0f\n", l, $6 / 1024}' "$tmp/time"
}
run() { # name, files...
  local name="$1"; shift
  local files=("$@")
  rss "$name plain" "$cota" tiles "${files[@]}" "${extra[@]}" -o "$tmp/plain"
  for n in 2 4; do
    out="$tmp/s$n"
    rss "$name N=$n plan step" "$cota" tiles "${files[@]}" "${extra[@]}" -o "$out" --plan --shards "$n"
    for i in $(seq 0 $((n - 1))); do
      rss "$name N=$n shard $i" "$cota" tiles "${files[@]}" "${extra[@]}" -o "$out" --shard "$i/$n"
    done
    rss "$name N=$n reduce" "$cota" tiles -o "$out" --reduce --shards "$n"
    diff -r "$tmp/plain" "$out" >/dev/null && echo "$name N=$n | byte-identical"
    rm -rf "$out"
  done
  rm -rf "$tmp/plain"
}
echo "run | peak RSS MB"
run mosaic2 "$data/srtm/N00E010.hgt" "$data/srtm/N00E011.hgt.zip"
run mosaic8 "${m8[@]}"
