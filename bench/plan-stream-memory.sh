#!/usr/bin/env bash
# Peak resident memory (GNU time -v) and wall time of the plan step
# (`cota tiles … --plan --shards N`, N = 2, 4, 8) of two cota binaries:
# BEFORE (the plan step reads the whole input and writes the coarse tiles)
# and AFTER (a build whose plan step streams its frame, PLAN_STEP_WRITES_COARSE
# = false in crates/cota-cli/src/tiles.rs). Checks that both write the same
# frame (cmp) and that the shards run after each write the same files (the
# coarse tiles, which only BEFORE writes, aside). Inputs as
# bench/shard-memory.sh: mosaic2 = ../shared/data/srtm/N00E010.hgt +
# N00E011.hgt.zip, mosaic8 = a relabelled 4×2 block of copies of them.
# usage: bench/plan-stream-memory.sh BEFORE AFTER
# (MENV="MALLOC_MMAP_THRESHOLD_=131072" runs the plan steps under that glibc setting)
set -eu
here="$(cd "$(dirname "$0")" && pwd)"
data="${COTA_SHARED_DATA:-$here/../../shared/data}"
before="$1"
after="$2"
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
rss() { # label, then the command: prints "label | MB | wall"
  local label="$1"; shift
  /usr/bin/time -v env ${MENV:-} "$@" >/dev/null 2>"$tmp/time" || { cat "$tmp/time" >&2; exit 1; }
  awk -v l="$label" '/Maximum resident/ {r = $6} /Elapsed \(wall/ {w = $8}
    END {printf "%s | %.0f MB | %s\n", l, r / 1024, w}' "$tmp/time"
}
run() { # name, files...
  local name="$1"; shift
  local files=("$@")
  for n in 2 4 8; do
    rss "$name N=$n before" "$before" tiles "${files[@]}" -o "$tmp/b$n" --plan --shards "$n"
    rss "$name N=$n after" "$after" tiles "${files[@]}" -o "$tmp/a$n" --plan --shards "$n"
    cmp "$tmp/b$n/.cota-shards-$n.json" "$tmp/a$n/.cota-shards-$n.json"
    for i in $(seq 0 $((n - 1))); do
      "$before" tiles "${files[@]}" -o "$tmp/b$n" --shard "$i/$n" >/dev/null 2>&1
      "$after" tiles "${files[@]}" -o "$tmp/a$n" --shard "$i/$n" >/dev/null 2>&1
    done
    differ=$(diff -r "$tmp/b$n" "$tmp/a$n" | grep -vc "^Only in $tmp/b$n" || true)
    [ "$differ" -eq 0 ] || { diff -r "$tmp/b$n" "$tmp/a$n" | head >&2; exit 1; }
    echo "$name N=$n | same frame, same shard files"
    rm -rf "$tmp/b$n" "$tmp/a$n"
  done
}
echo "run | peak RSS | wall"
run mosaic2 "$data/srtm/N00E010.hgt" "$data/srtm/N00E011.hgt.zip"
run mosaic8 "${m8[@]}"
