"""The Python per-tile quantized-mesh pipeline users run today, on cota's lattice.

As dem-tiler does for each tile: a 65x65 height grid for the tile, Martini
(pymartini) or Delatin (pydelatin) at the tile's error, positions rescaled to
the tile's bounds (`rescale_positions`, y flipped), `quantized_mesh_encoder.encode`
with the tile's bounds, one file per tile. The grid is read from the lattice
`tiles-peers export` wrote (cota's resampled source, so both tools mesh the same
samples; the peers' time leaves out reading and resampling the source, which
cota's time includes). At the maximum zoom the 65x65 grid is exactly the
lattice's samples of the tile; at coarser zooms every (T_z/64)-th sample.

Usage: python tiles_peers.py LATTICE_DIR OUT_DIR {martini,delatin} FACTOR WORKERS
(the tile's error is FACTOR times cota's bound for its zoom).
"""

import json
import os
import sys
from multiprocessing import Pool

import numpy as np
import quantized_mesh_encoder
from pydelatin import Delatin
from pymartini import Martini, rescale_positions

LATTICE = None
META = None


def load(lattice_dir):
    global LATTICE, META
    with open(os.path.join(lattice_dir, "lattice.json")) as f:
        META = json.load(f)
    LATTICE = np.fromfile(os.path.join(lattice_dir, "lattice.f32"), dtype="<f4").reshape(
        META["height"], META["width"]
    )


def grid_of(z, x, y):
    """The tile's 65x65 heights (row 0 north), 0 m beyond the lattice's window."""
    cells = META["tile_cells"] << (META["max_zoom"] - z)
    step = cells // 64
    ox, oy = META["origin"]
    col0 = x * cells - ox
    row0 = ((1 << z) - 1 - y) * cells - oy
    cols = col0 + step * np.arange(65)
    rows = row0 + step * np.arange(65)
    out = np.zeros((65, 65), dtype=np.float32)
    cin = (cols >= 0) & (cols < META["width"])
    rin = (rows >= 0) & (rows < META["height"])
    out[np.ix_(rin, cin)] = LATTICE[np.ix_(rows[rin], cols[cin])]
    return out


def bounds_of(z, x, y):
    size = 180.0 / (1 << z)
    w, s = -180.0 + x * size, -90.0 + y * size
    return (w, s, w + size, s + size)


def one(job):
    tool, factor, out, z, x, y, bound = job
    terrain = grid_of(z, x, y)
    if tool == "martini":
        tile = Martini(65).create_tile(terrain)
        vertices, triangles = tile.get_mesh(bound * factor)
    else:
        tin = Delatin(terrain, width=65, height=65, max_error=bound * factor)
        vertices, triangles = tin.vertices, tin.triangles
    positions = rescale_positions(vertices, terrain, bounds=bounds_of(z, x, y), flip_y=True)
    path = os.path.join(out, str(z), str(x))
    os.makedirs(path, exist_ok=True)
    with open(os.path.join(path, f"{y}.terrain"), "wb") as f:
        quantized_mesh_encoder.encode(f, positions, triangles, bounds=bounds_of(z, x, y))
    return 1


def main():
    lattice_dir, out, tool, factor, workers = sys.argv[1:6]
    load(lattice_dir)
    jobs = [
        (tool, float(factor), out, z["zoom"], x, y, z["max_error_m"])
        for z in META["zooms"]
        for x in range(z["x0"], z["x1"] + 1)
        for y in range(z["y0"], z["y1"] + 1)
    ]
    if int(workers) > 1:
        with Pool(int(workers), initializer=load, initargs=(lattice_dir,)) as pool:
            done = sum(pool.imap_unordered(one, jobs, chunksize=16))
    else:
        done = sum(map(one, jobs))
    print(f"{done} tiles", file=sys.stderr)


if __name__ == "__main__":
    main()
