"""Type stubs of the cota package (the extension module cota._cota)."""

import os
from typing import Literal, Sequence, TypedDict, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, "os.PathLike[str]"]

class Metrics(TypedDict):
    """Exact error of a mesh against its grid, over every sample."""

    max_error_m: float
    max_error_at: tuple[int, int]  # (column, row)
    rmse_m: float
    mean_abs_error_m: float
    samples: int
    uncovered: int

class GeoRef(TypedDict):
    crs: str  # "EPSG:4326", a description, or "unknown"
    origin_x: float
    origin_y: float
    pixel_x: float
    pixel_y: float
    pixel_is: Literal["area", "point"]
    known: bool

class CotaError(Exception):
    """Base class of cota's errors."""

class ReadError(CotaError):
    """A DEM file could not be read or joined (the message names the file)."""

class MeshError(CotaError):
    """A grid could not be prepared or meshed."""

class CheckError(CotaError):
    """The invariant checker found a violation."""

class WriteError(CotaError):
    """A mesh file could not be written (nothing is left behind)."""

def read(paths: Union[_Path, Sequence[_Path]], fill: bool = True) -> Dem:
    """Read one DEM file or several adjacent tiles into one grid.

    ``fill=True`` fills voids harmonically (as ``cota mesh``); ``fill=False``
    leaves them NaN. Raises ReadError. Releases the GIL.
    """

class TilesReport(TypedDict):
    """What ``tiles`` wrote."""
    tiles: int
    written: int
    skipped: int
    bytes: int
    files_read: list[str] | None
    """The input files a shard after ``tiles_plan_step`` read; None otherwise."""

class PlanStepReport(TypedDict):
    """What ``tiles_plan_step`` wrote (the frame and the band corners; no tile)."""
    band_zoom: int
    coarse_tiles: int
    """The tiles coarser than the band zoom, which ``tiles_reduce`` cuts."""
    written: int
    """0: the plan step writes no tile."""
    skipped: int
    files: list[tuple[str, tuple[int, int, int, int]]]
    """Each input's samples in the mosaic ``(c0, r0, c1, r1)``; empty: shards read every file."""

class ShardPlan(TypedDict):
    """One shard of ``tiles_plan``: its tiles as ``(zoom, x0, x1, y0, y1)``, tile addresses, TMS,
    inclusive (a range across the antimeridian as its two parts)."""
    shard: int
    shards: int
    tiles: int
    ranges: list[tuple[int, int, int, int, int]]

def tiles(
    paths: Union[_Path, Sequence[_Path]],
    out: _Path,
    *,
    min_zoom: int = 0,
    max_zoom: int | None = None,
    tile_cells: int = 64,
    error_factor: float | None = None,
    max_error_m_at_max_zoom: float | None = None,
    normals: bool = False,
    watermask: bool = False,
    metadata: bool = False,
    gzip: bool = False,
    force: bool = False,
    check: bool = False,
    shard: tuple[int, int] | None = None,
    format: Literal["quantized-mesh", "3dtiles"] = "quantized-mesh",
    meshopt: bool = False,
    skirts: bool = True,
) -> TilesReport:
    """Write a quantized-mesh pyramid under ``out``, byte for byte as ``cota tiles``.

    ``out`` ending in ``.mbtiles``: one MBTiles archive. ``format="3dtiles"``: 3D Tiles
    terrain (``meshopt``: EXT_meshopt_compression; ``skirts``: a skirt primitive per
    GLB), into one 3D Tiles Archive when ``out`` ends in ``.3tz``. Settings a format
    cannot hold raise ValueError before any work.

    ``shard=(i, n)``: only shard ``i`` of ``n`` and its record; ``tiles_reduce``
    then writes ``layer.json``. After ``tiles_plan_step`` (its frame under ``out``)
    the shard reads only the input files its part of the lattice needs, and
    refuses a frame made with other settings. Raises ReadError, MeshError,
    WriteError. Releases the GIL.
    """

def tiles_plan_step(
    paths: Union[_Path, Sequence[_Path]],
    out: _Path,
    shards: int,
    *,
    min_zoom: int = 0,
    max_zoom: int | None = None,
    tile_cells: int = 64,
    error_factor: float | None = None,
    max_error_m_at_max_zoom: float | None = None,
    normals: bool = False,
    watermask: bool = False,
    metadata: bool = False,
    gzip: bool = False,
    force: bool = False,
    check: bool = False,
) -> PlanStepReport:
    """The plan step of ``cota tiles --plan --shards n``: read the inputs one shard's
    part at a time (parts ``tiles_plan_part`` already wrote are not read again), write
    the frame ``out/.cota-shards-n.json`` and the band zoom's tile-corner heights.

    Idempotent. Then ``tiles(..., shard=(i, n))`` with the same settings reads only
    its part's files, writes its tiles of the band zoom and finer and its partial
    maxima of the coarser ones, which ``tiles_reduce`` merges and cuts. The tile
    settings (``normals`` … ``check``) are the shards'. Raises ReadError,
    MeshError, WriteError. Releases the GIL.
    """

class PlanLayoutReport(TypedDict):
    """What ``tiles_plan_layout`` found."""
    streamed: bool
    """False when every shard must read every file: the plan step then reads the whole input and has no parts."""
    files: int

class PlanPartReport(TypedDict):
    """What ``tiles_plan_part`` did."""
    streamed: bool
    """False: nothing to do in parts (``tiles_plan_step`` reads the whole input)."""
    skipped: bool
    """Its file ``out/.cota-plan-i-of-n.bin`` was already there."""
    files_read: list[str]

def tiles_plan_layout(
    paths: Union[_Path, Sequence[_Path]],
    out: _Path,
    shards: int,
    *,
    min_zoom: int = 0,
    max_zoom: int | None = None,
    tile_cells: int = 64,
    error_factor: float | None = None,
    max_error_m_at_max_zoom: float | None = None,
) -> PlanLayoutReport:
    """The plan step's layout (``cota tiles --plan --layout``): each input read alone
    for its shape; ``out/.cota-layout-n.json`` written (kept when there). Run once
    before the ``tiles_plan_part`` tasks. Raises ReadError, WriteError. Releases the GIL.
    """

def tiles_plan_part(
    paths: Union[_Path, Sequence[_Path]],
    out: _Path,
    shards: int,
    part: int,
    *,
    min_zoom: int = 0,
    max_zoom: int | None = None,
    tile_cells: int = 64,
    error_factor: float | None = None,
    max_error_m_at_max_zoom: float | None = None,
) -> PlanPartReport:
    """Part ``part`` of the plan step (``cota tiles --plan --part i``): shard ``part``'s
    files read and its part resampled for the lattice's statistics and band corners,
    into ``out/.cota-plan-i-of-n.bin`` (the layout made first when missing).
    Idempotent; independent of the other parts, so they run in parallel; then
    ``tiles_plan_step`` merges them. Raises ReadError, WriteError. Releases the GIL.
    """

def tiles_plan(
    paths: Union[_Path, Sequence[_Path]],
    shards: int,
    *,
    min_zoom: int = 0,
    max_zoom: int | None = None,
    tile_cells: int = 64,
    error_factor: float | None = None,
    max_error_m_at_max_zoom: float | None = None,
) -> list[ShardPlan]:
    """The deterministic shard plan of ``cota tiles --plan --shards n``."""

def tiles_reduce(out: _Path, shards: int) -> int:
    """Check the ``shards`` shards' records; after a plan step, cut the tiles coarser than the band zoom from the shards' partial maxima; write ``layer.json``, remove the records; the pyramid's tile count."""

def shard_frame(out: _Path, shards: int) -> str:
    """The path of the plan step's frame (present once the plan step is done)."""

def shard_record(out: _Path, index: int, shards: int) -> str:
    """The path of shard ``index``'s record (present once the shard is complete)."""

class Dem:
    """A DEM read by ``cota.read``."""

    @property
    def heights(self) -> npt.NDArray[np.float32]:
        """Heights in metres, shape (rows, columns), row 0 north; read-only."""
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def voids(self) -> int:
        """Void samples before any fill."""
    @property
    def filled(self) -> bool: ...
    @property
    def files(self) -> list[str]: ...
    @property
    def cell_size_m(self) -> tuple[float, float]: ...
    @property
    def georef(self) -> GeoRef: ...
    def bitree(self) -> Bitree:
        """The error hierarchy of this DEM (shares its grid). Raises MeshError on voids."""

class Bitree:
    """Exact errors of the right-triangle hierarchy of a grid, built once."""

    def __init__(
        self,
        heights: npt.NDArray[Union[np.float32, np.float64, np.int16]],
        cell_size_m: float = 30.0,
        voids: Literal["fill", "refuse"] = "fill",
        nodata: Union[float, None] = None,
    ) -> None:
        """Build from a 2-D array (rows x columns, row 0 north), any strides.

        float64 is rounded to float32; int16 is exact. NaN (and values equal
        to ``nodata``) are voids: filled harmonically with ``voids="fill"``,
        refused (MeshError) with ``voids="refuse"``; an all-NaN array raises
        MeshError. Wrong dtype: TypeError; wrong ndim or empty: ValueError.
        """
    def extract(
        self,
        *,
        max_error: Union[float, None] = None,
        max_triangles: Union[int, None] = None,
        tin: bool = False,
    ) -> Mesh:
        """The coarsest conforming mesh within ``max_error`` m at every sample,
        or the most accurate with at most ``max_triangles`` triangles.
        ``tin=True``: cota's irregular TIN under the same exact bound (fewer
        triangles, slower)."""
    def check(self, mesh: Mesh, bound: float) -> Metrics:
        """Prove coverage, no T-junction and |error| <= bound at every sample
        (plus, for a TIN or a mesh from arrays, no vertex inside an edge and
        every vertex used); raises CheckError."""
    def metrics(self, mesh: Mesh) -> Metrics:
        """Exact error of ``mesh`` over every sample."""
    def mesh_from_arrays(self, vertices: npt.ArrayLike, triangles: npt.ArrayLike) -> Mesh:
        """A Mesh of this grid from another mesher's arrays (vertices: integer column,
        row in the first two columns; heights are the grid's), to measure or check it.
        Its ``threshold_m`` is NaN. Raises ValueError for a vertex off the samples or
        an index out of range."""
    @property
    def heights(self) -> npt.NDArray[np.float32]:
        """The (filled) heights built on; read-only."""
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def voids_filled(self) -> int: ...

class Mesh:
    """A conforming mesh of a grid, every vertex on a sample."""

    @property
    def vertices(self) -> npt.NDArray[np.float64]:
        """(n, 3): column, row (from the north), height in metres; read-only."""
    @property
    def triangles(self) -> npt.NDArray[np.uint32]:
        """(m, 3) indices into ``vertices``, counter-clockwise from above; read-only."""
    @property
    def threshold_m(self) -> float: ...
    @property
    def vertex_count(self) -> int: ...
    @property
    def triangle_count(self) -> int: ...
    def write(
        self,
        path: _Path,
        *,
        coords: Literal["local", "grid"] = "local",
        quantize: bool = False,
    ) -> None:
        """Write .obj/.ply/.stl/.glb atomically; raises WriteError."""
    def __len__(self) -> int: ...
