#!/usr/bin/env bash
# Prepares a COTA_BIG_DATA directory of real SRTM tiles for the large-grid
# benchmarks (crates/cota-bench/src/big.rs) from a local git repository that
# holds .hgt / .hgt.zip / .hgt.gz tiles in its newest commit. Nothing is
# downloaded here, and nothing it writes may be committed to cota.
#
# Usage: bench/get-big-data.sh GIT_DIR OUT_DIR
#        COTA_BIG_DATA=OUT_DIR cargo run --release -p cota-bench --bin memory
#
# Every tile whose samples make a 1201² (3") or 3601² (1") grid is written to
# OUT_DIR (.hgt.gz decompressed to .hgt, .hgt.zip kept as is); stubs and other
# sizes are skipped. The benchmarks then take the first 3601² tile as
# `srtm3601` and mosaic the 1201² tiles at their real positions (they must
# form a contiguous block; 8 or more are needed to replace the relabelled
# `mosaic8`).
#
# The one real 3601² tile found when this was written is S46W066 (SRTM 1",
# Patagonian coast) in the test data of the Go package asmyasnikov/srtm
# (testdata/S46W066.hgt.gz): real, but 98.6 % of its samples are sea at 0 m
# (heights -3..146 m), so its meshes are tiny and it mostly measures the
# memory of read and build. Its other tiles are 130-byte stubs.
set -u
if [ $# -ne 2 ]; then
  echo "usage: $0 GIT_DIR OUT_DIR" >&2
  exit 2
fi
git_dir="$1"
out="$2"
mkdir -p "$out"
n=0
while IFS= read -r path; do
  base="$(basename "$path")"
  case "$base" in
    *.gz)
      tmp="$out/${base%.gz}"
      { git --git-dir="$git_dir" show "HEAD:$path" 2>/dev/null | gzip -dc >"$tmp" 2>/dev/null; } || { rm -f "$tmp"; continue; }
      size=$(wc -c <"$tmp")
      ;;
    *.zip)
      tmp="$out/$base"
      git --git-dir="$git_dir" show "HEAD:$path" >"$tmp" 2>/dev/null || { rm -f "$tmp"; continue; }
      size=$(python3 -c 'import sys, zipfile; z = zipfile.ZipFile(sys.argv[1]); print(sum(i.file_size for i in z.infolist()))' "$tmp" 2>/dev/null || echo 0)
      ;;
    *)
      tmp="$out/$base"
      git --git-dir="$git_dir" show "HEAD:$path" >"$tmp" 2>/dev/null || { rm -f "$tmp"; continue; }
      size=$(wc -c <"$tmp")
      ;;
  esac
  if [ "$size" = 2884802 ] || [ "$size" = 25934402 ]; then
    echo "get-big-data: $path -> $tmp ($size bytes of samples)"
    n=$((n + 1))
  else
    rm -f "$tmp"
  fi
done < <(git --git-dir="$git_dir" ls-tree -r --name-only HEAD | grep -iE '\.hgt(\.zip|\.gz)?$')
echo "get-big-data: $n tile(s) in $out; use COTA_BIG_DATA=$out"
