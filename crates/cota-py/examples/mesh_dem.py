"""Mesh a DEM from Python, notebook style.

    python crates/cota-py/examples/mesh_dem.py [DEM] [OUT.glb]

Reads the DEM with rasterio when it is installed (heights, nodata and pixel size from
GDAL), else with cota.read (pure Rust: SRTM, GeoTIFF, PNG, ESRI ASCII). Default DEM:
the bundled tile fixtures/S29W072.hgt.zip.
"""

import sys
import time
from pathlib import Path

import numpy as np

import cota

root = Path(__file__).resolve().parents[3]
path = Path(sys.argv[1]) if len(sys.argv) > 1 else root / "fixtures" / "S29W072.hgt.zip"
out = Path(sys.argv[2]) if len(sys.argv) > 2 else Path("example.glb")

# %% Read: rasterio if present, else cota.read
try:
    import rasterio

    with rasterio.open(path) as src:
        heights = src.read(1, masked=True).astype(np.float32).filled(np.nan)
        cell = abs(src.res[0]) * (111_320.0 if src.crs and src.crs.is_geographic else 1.0)
    tree = cota.Bitree(heights, cell_size_m=cell)  # NaN voids filled harmonically
    print(f"rasterio: {heights.shape}, {tree.voids_filled} voids filled")
except ImportError:
    dem = cota.read(path)
    print(f"cota.read: {dem}, georef {dem.georef['crs']}, cell {dem.cell_size_m}")
    tree = dem.bitree()

# %% Meshes at several bounds: every one proved at every sample
for bound in (1.0, 5.0, 20.0):
    t0 = time.perf_counter()
    mesh = tree.extract(max_error=bound)
    dt = (time.perf_counter() - t0) * 1e3
    report = tree.check(mesh, bound)
    print(
        f"{bound:5.1f} m: {mesh.triangle_count:8d} triangles in {dt:6.1f} ms, "
        f"max {report['max_error_m']:.3f} m, RMSE {report['rmse_m']:.3f} m"
    )

# %% numpy arrays, and a file
v, t = mesh.vertices, mesh.triangles
print(f"vertices {v.shape} {v.dtype}, triangles {t.shape} {t.dtype}")
mesh.write(out)
print(f"wrote {out}")
