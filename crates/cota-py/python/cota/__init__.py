"""cota: terrain meshes whose error is guaranteed at every grid sample.

Python bindings of the cota Rust library (cota-core, cota-io). Typical use::

    import cota
    dem = cota.read("N00E010.hgt.zip")          # or a list of adjacent tiles
    tree = dem.bitree()                         # exact errors, built once
    mesh = tree.extract(max_error=5.0)          # or max_triangles=...
    tree.check(mesh, 5.0)                       # proves the bound at every sample
    mesh.vertices, mesh.triangles               # numpy (n, 3) float64, (m, 3) uint32
    mesh.write("x.glb")

From numpy: ``cota.Bitree(heights, cell_size_m=30.0)`` with a 2-D float32,
float64 or int16 array; NaN marks voids (filled by default, see ``Bitree``).
Long calls release the GIL; errors are ``cota.CotaError`` subclasses carrying
cota's messages, bad arrays ``TypeError`` / ``ValueError``.

Tile pyramids: ``cota.tiles(paths, out, ...)`` (as ``cota tiles``), one shard of
one with ``shard=(i, n)``, and ``cota.dask.build_pyramid`` across a Dask cluster.
"""

from ._cota import (
    Bitree,
    CheckError,
    CotaError,
    Dem,
    Mesh,
    MeshError,
    ReadError,
    WriteError,
    read,
    shard_frame,
    shard_record,
    tiles,
    tiles_plan,
    tiles_plan_layout,
    tiles_plan_part,
    tiles_plan_step,
    tiles_reduce,
)

__all__ = [
    "Bitree",
    "CheckError",
    "CotaError",
    "Dem",
    "Mesh",
    "MeshError",
    "ReadError",
    "WriteError",
    "read",
    "shard_frame",
    "shard_record",
    "tiles",
    "tiles_plan",
    "tiles_plan_layout",
    "tiles_plan_part",
    "tiles_plan_step",
    "tiles_reduce",
]
