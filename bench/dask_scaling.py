"""Throughput of ``cota.dask.build_pyramid`` from 1 to K Dask workers (issue 20).

The input is the 8-tile relabelled mosaic of ``bench/shard-memory.sh`` (a 4x2
block of copies of the two void-free SRTM tiles N00E010 and N00E011, real
samples at false positions). Each worker is one process with one thread and a
one-thread rayon pool (``RAYON_NUM_THREADS=1``), so K workers use K cores: the
Dask deployment of one worker per core. Every pyramid is compared byte for byte
with the first one. ``COTA_REPS`` rounds (default 3), each running every K in
turn on clusters started beforehand; the speed-up is the median of the
rounds' ratios.

usage: python bench/dask_scaling.py [K ...]   (default: 1 2)
env:   COTA_SHARED_DATA (../shared/data), COTA_MAX_ZOOM (12), COTA_SHARDS (8), COTA_REPS (3)
"""

from __future__ import annotations

import contextlib
import filecmp
import os
import shutil
import statistics
import sys
import tempfile
import time
import zipfile
from pathlib import Path

os.environ["RAYON_NUM_THREADS"] = "1"

import cota.dask  # noqa: E402
import distributed  # noqa: E402

HERE = Path(__file__).resolve().parent
DATA = Path(os.environ.get("COTA_SHARED_DATA", HERE.parent.parent / "shared" / "data"))


def mosaic8(tmp: Path) -> list[Path]:
    a = (DATA / "srtm" / "N00E010.hgt").read_bytes()
    with zipfile.ZipFile(DATA / "srtm" / "N00E011.hgt.zip") as z:
        b = z.read(z.namelist()[0])
    out = []
    for lat in (10, 9):
        for lon in (20, 21, 22, 23):
            p = tmp / f"N{lat:02d}E{lon:03d}.hgt"
            p.write_bytes(b if (lon + lat) % 2 else a)
            out.append(p)
    return out


def same_tree(a: Path, b: Path) -> bool:
    c = filecmp.dircmp(a, b)
    if c.left_only or c.right_only or c.diff_files or c.funny_files:
        return False
    return all(same_tree(a / d, b / d) for d in c.common_dirs)


def main() -> None:
    ks = [int(k) for k in sys.argv[1:]] or [1, 2]
    max_zoom = int(os.environ.get("COTA_MAX_ZOOM", "12"))
    shards = int(os.environ.get("COTA_SHARDS", "8"))
    reps = int(os.environ.get("COTA_REPS", "3"))
    tmp = Path(tempfile.mkdtemp())
    try:
        inputs = mosaic8(tmp)
        with contextlib.ExitStack() as stack:
            clients = {k: stack.enter_context(distributed.Client(stack.enter_context(
                distributed.LocalCluster(n_workers=k, threads_per_worker=1, processes=True,
                                         dashboard_address=None)))) for k in ks}
            first, times, tiles = None, {k: [] for k in ks}, {}
            # Rounds of every K in turn, so that a drift of this shared
            # machine's speed touches every K alike.
            for r in range(reps):
                for k in ks:
                    out = tmp / f"k{k}r{r}"
                    t0 = time.perf_counter()
                    rep = cota.dask.build_pyramid(inputs, out, client=clients[k],
                                                  shards=shards, max_zoom=max_zoom)
                    times[k].append(time.perf_counter() - t0)
                    tiles[k] = rep["tiles"]
                    if first is None:
                        first = out
                    else:
                        assert same_tree(first, out), f"{out} differs from {first}"
                        shutil.rmtree(out)
        base = times[ks[0]]
        print(f"mosaic8, max zoom {max_zoom}, {shards} shards, {reps} rounds, one thread per worker")
        print(f"| workers | seconds (median) | tiles | speed-up (median of the rounds' ratios) |")
        print("|---:|---:|---:|---:|")
        for k in ks:
            ratio = statistics.median(b / t for b, t in zip(base, times[k]))
            print(f"| {k} | {statistics.median(times[k]):.2f} | {tiles[k]} | {ratio:.2f}x |")
        for k in ks:
            print(f"workers {k}, each round (s): " + ", ".join(f"{t:.2f}" for t in times[k]))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
