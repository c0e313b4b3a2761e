"""Throughput of ``cota.dask.build_pyramid`` from 1 to K Dask workers (issue 20).

The input is the 8-tile relabelled mosaic of ``bench/shard-memory.sh`` (a 4x2
block of copies of the two void-free SRTM tiles N00E010 and N00E011, real
samples at false positions). Each worker is one process with one thread and a
one-thread rayon pool (``RAYON_NUM_THREADS=1``), so K workers use K cores: the
Dask deployment of one worker per core. Every pyramid is compared byte for byte
with the first one. ``COTA_REPS`` rounds (default 3), each running every K in
turn on clusters started beforehand; the speed-up is the median of the
rounds' ratios.

Each K runs with the plan step in parts (``plan_in_parts=True``, the
default: plan-part tasks through ``client.map``) and, for comparison, as one
task reading the parts in turn (``plan_in_parts=False``), in the same rounds.

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
            runs = [(k, parts) for k in ks for parts in (True, False)]
            first, times, tiles = None, {run: [] for run in runs}, {}
            # Rounds of every run in turn, so that a drift of this shared
            # machine's speed touches every run alike.
            for r in range(reps):
                for k, parts in runs:
                    out = tmp / f"k{k}{parts}r{r}"
                    t0 = time.perf_counter()
                    rep = cota.dask.build_pyramid(inputs, out, client=clients[k],
                                                  shards=shards, max_zoom=max_zoom,
                                                  plan_in_parts=parts)
                    times[(k, parts)].append(time.perf_counter() - t0)
                    tiles[(k, parts)] = rep["tiles"]
                    if first is None:
                        first = out
                    else:
                        assert same_tree(first, out), f"{out} differs from {first}"
                        shutil.rmtree(out)
        print(f"mosaic8, max zoom {max_zoom}, {shards} shards, {reps} rounds, one thread per worker")
        print("| workers | plan step | seconds (median) | tiles | speed-up (median of the rounds' ratios) |")
        print("|---:|---|---:|---:|---:|")
        for k, parts in runs:
            base = times[(ks[0], parts)]
            mine = times[(k, parts)]
            ratio = statistics.median(b / t for b, t in zip(base, mine))
            how = "in parts" if parts else "one task"
            print(f"| {k} | {how} | {statistics.median(mine):.2f} | {tiles[(k, parts)]} | {ratio:.2f}x |")
        for (k, parts), ts in times.items():
            how = "in parts" if parts else "one task"
            print(f"workers {k}, plan step {how}, each round (s): " + ", ".join(f"{t:.2f}" for t in ts))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
