#!/usr/bin/env bash
# `cota tiles` at scale (issue 29, item 6): a relabelled 8×8 mosaic of the
# shared 3" SRTM tiles (64 files of 1201², 9601×9601 = 92.2 M samples),
# zooms 0-12, on the machine's cores:
#   plain    one `cota tiles` process over the 64 files;
#   sharded  `--plan --shards N`, then `--shard I/N` for each I in turn, then
#            `--reduce --shards N` (each process alone on the cores);
#   dask     `cota.dask.build_pyramid` with N shards on a LocalCluster of one
#            single-threaded worker per core (SCALE_DASK=1 and the `cota`
#            Python package importable by $PYTHON).
# For each process: wall time, tiles written, tiles per second and peak RSS
# (GNU time -v, "Maximum resident set size"; for Dask tasks, the worker's
# VmHWM reset before each task through /proc/self/clear_refs). Each shard's
# peak is set beside what its part holds by construction, from its --json
# report: its lattice window (f32, 4 B a point), its hierarchy (the bitree's
# u16 error codes and the u16 source-error codes, 4 B a point) and its source
# part (the files it read, mosaicked as f32, 4 B a sample). Every sharded
# pyramid is compared with the plain one (diff -rq).
#
# The mosaic: tile (row r, column c) of the block N17..N10 × E020..E027 is a
# copy of the shared 3" tile number (3r + c) mod 7 (N00E010, N00E011,
# N41E001, N42E001, N49E011, N50E011, S29W072), its voids (7,835 in all in
# the seven) filled from the nearest valid sample of the row, so that each
# shard reads only its own files (a mosaic with voids makes every shard read
# every file). Real samples at false positions: the seams between copies are
# artificial cliffs, averaged where their shared edges disagree.
#
# usage: bench/scale-mosaic.sh [COTA]    (default: $CARGO_TARGET_DIR or
#        target, then release/cota, built first with cargo build --release)
# env:   COTA_SHARED_DATA (../shared/data), SCALE_DIR (scratch parent, default
#        the target dir), SCALE_SHARDS (4), SCALE_THREADS (nproc), SCALE_DASK
#        (0), PYTHON (python3), SCALE_MAX_ZOOM (12)
set -eu
here="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$here")"
target="${CARGO_TARGET_DIR:-$root/target}"
cota="${1:-}"
if [ -z "$cota" ]; then
  (cd "$root" && cargo build --release -q -p cota-cli --bin cota) || exit 1
  cota="$target/release/cota"
fi
data="${COTA_SHARED_DATA:-$root/../shared/data}"
parent="${SCALE_DIR:-$target}"
mkdir -p "$parent"
scratch="$(mktemp -d "$parent/scale-mosaic.XXXXXX")"
trap 'rm -rf "$scratch"' EXIT
"${PYTHON:-python3}" "$here/scale_mosaic.py" "$scratch" "$cota" "$data"
