"""cota against pymartini and pydelatin from Python, in one run (issue 20, item 5).

    bench/python-peers.sh [DEM ...]          # makes the venv, then runs this
    python bench/python_peers.py [DEM ...]   # in a venv with cota, pymartini, pydelatin

For each 1201x1201 DEM (default: the bundled fixtures/S29W072.hgt.zip; the heights as
cota.read gives them, voids filled) and each E (env COTA_PY_E, default 5 m):
* time per mesh: cota Bitree(heights) + extract(max_error=E) (and with tin=True), pymartini
  create_tile + get_mesh(E) (Martini(n) itself, built once per size, apart), pydelatin
  Delatin(heights, max_error=E); medians of COTA_PY_RUNS runs (default 5; pydelatin 1);
* triangles at equal true error: every mesh measured by cota at every sample
  (Bitree.metrics); pymartini's threshold lowered by bisection until its true error
  is at most E.
pymartini needs a (2^k+1)^2 grid: on the 1201^2 tile it meshes the tile edge-padded to
2049^2 (timed only); the equal-error counts of all three are on the 1025^2 north-west
crop, where pymartini runs natively.
"""

import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from pydelatin import Delatin
from pymartini import Martini

import cota

ROOT = Path(__file__).resolve().parents[1]
RUNS = int(os.environ.get("COTA_PY_RUNS", "5"))
ES = [float(e) for e in os.environ.get("COTA_PY_E", "5").split(",")]


def timed(fn, runs):
    """Median milliseconds of `runs` calls, and the last result."""
    times, out = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        out = fn()
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times), out


def cota_mesh(h, e, tin=False):
    return cota.Bitree(h).extract(max_error=e, tin=tin)


def martini_mesh(martini, h, e):
    vertices, triangles = martini.create_tile(h).get_mesh(e)
    return vertices, triangles  # (n, 2) uint16 column, row; (m, 3) uint32


def delatin_mesh(h, e):
    tin = Delatin(h, width=h.shape[1], height=h.shape[0], max_error=e)
    v = tin.vertices[:, :2].astype(np.float64)
    v[:, 1] = h.shape[0] - 1 - v[:, 1]  # pydelatin's y points north
    return v, tin.triangles


def true_error(tree, vertices, triangles):
    return tree.metrics(tree.mesh_from_arrays(vertices, triangles))["max_error_m"]


def martini_at_true_error(tree, martini, h, e):
    """Triangles of pymartini's mesh at the largest threshold whose true error is <= e."""
    tile = martini.create_tile(h)
    lo, hi = 0.0, e  # true error at lo = 0 is 0
    for _ in range(14):
        mid = (lo + hi) / 2
        v, t = tile.get_mesh(mid)
        if true_error(tree, v, t) <= e:
            lo = mid
        else:
            hi = mid
    v, t = tile.get_mesh(lo)
    return lo, len(t)


def tile_row(name, h, e, martini2049):
    ms_cota, mesh = timed(lambda: cota_mesh(h, e), RUNS)
    ms_tin, tin = timed(lambda: cota_mesh(h, e, tin=True), RUNS)
    pad = np.pad(h, ((0, 2049 - h.shape[0]), (0, 2049 - h.shape[1])), mode="edge")
    ms_martini, _ = timed(lambda: martini_mesh(martini2049, pad, e), RUNS)
    ms_delatin, (v, t) = timed(lambda: delatin_mesh(h, e), 1)
    tree = cota.Bitree(h)
    err_d = true_error(tree, v, t)
    return (
        f"| {name} {h.shape[1]}² | {e:g} | {ms_cota:.1f} ({mesh.triangle_count:,}) "
        f"| {ms_tin:.1f} ({tin.triangle_count:,}) "
        f"| {ms_martini:.1f} (2049² padded) | {ms_delatin:,.0f} ({len(t):,}; {err_d:.3f} m) "
        f"| {ms_martini / ms_cota:.1f}× | {ms_delatin / ms_cota:.0f}× | {ms_delatin / ms_tin:.1f}× "
        f"| {tin.triangle_count / len(t):.2f} |"
    )


def crop_row(name, h, e, martini1025):
    ms_cota, mesh = timed(lambda: cota_mesh(h, e), RUNS)
    ms_martini, (vm, tm) = timed(lambda: martini_mesh(martini1025, h, e), RUNS)
    ms_delatin, (vd, td) = timed(lambda: delatin_mesh(h, e), 1)
    tree = cota.Bitree(h)
    err_c = tree.check(mesh, e)["max_error_m"]
    err_m, err_d = true_error(tree, vm, tm), true_error(tree, vd, td)
    thr, tris_m = martini_at_true_error(tree, martini1025, h, e)
    return (
        f"| {name} crop {h.shape[1]}² | {e:g} | {ms_cota:.1f} ({mesh.triangle_count:,}; {err_c:.3f} m) "
        f"| {ms_martini:.1f} ({len(tm):,}; {err_m:.3f} m) | {ms_delatin:,.0f} ({len(td):,}; {err_d:.3f} m) "
        f"| {ms_martini / ms_cota:.1f}× | {ms_delatin / ms_cota:.0f}× "
        f"| {tris_m:,} at {thr:.4f} | {mesh.triangle_count / tris_m:.2f} | {mesh.triangle_count / len(td):.2f} |"
    )


def main():
    paths = [Path(p) for p in sys.argv[1:]] or [ROOT / "fixtures" / "S29W072.hgt.zip"]
    t0 = time.perf_counter()
    martini2049 = Martini(2049)
    ms_m2049 = (time.perf_counter() - t0) * 1e3
    t0 = time.perf_counter()
    martini1025 = Martini(1025)
    ms_m1025 = (time.perf_counter() - t0) * 1e3
    print(f"Martini(2049) {ms_m2049:.0f} ms, Martini(1025) {ms_m1025:.0f} ms (once per size)\n")
    print("| grid | E (m) | cota build+extract ms (tris) | cota TIN ms (tris) | pymartini tile+mesh ms "
          "| pydelatin ms (tris; true err) | martini/cota | delatin/cota | delatin/cota TIN | TIN/delatin tris |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    heights = {p.name: np.array(cota.read(p).heights) for p in paths}
    for name, h in heights.items():
        for e in ES:
            print(tile_row(name, h, e, martini2049), flush=True)
    print()
    print("| grid | E (m) | cota ms (tris; true err) | pymartini ms (tris; true err) | pydelatin ms (tris; true err) "
          "| martini/cota | delatin/cota | pymartini tris at true err ≤ E (threshold) | cota/martini tris | cota/delatin tris |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, h in heights.items():
        crop = np.ascontiguousarray(h[:1025, :1025])
        for e in ES:
            print(crop_row(name, crop, e, martini1025), flush=True)


if __name__ == "__main__":
    main()
