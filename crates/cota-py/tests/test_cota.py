"""pytest suite of the cota bindings, on the bundled SRTM tile (fixtures/S29W072.hgt.zip:
1201x1201, 21 voids). Every mesh is proved by cota's checker at every sample; one is also
re-measured here by an independent numpy rasterizer."""

from pathlib import Path

import numpy as np
import pytest

import cota

TILE = Path(__file__).resolve().parents[3] / "fixtures" / "S29W072.hgt.zip"


@pytest.fixture(scope="module")
def dem():
    return cota.read(TILE)


@pytest.fixture(scope="module")
def tree(dem):
    return dem.bitree()


def same_mesh(a, b):
    return np.array_equal(a.vertices, b.vertices) and np.array_equal(a.triangles, b.triangles)


# --- reading -------------------------------------------------------------------------------


def test_read_tile(dem):
    assert (dem.width, dem.height) == (1201, 1201)
    assert dem.heights.shape == (1201, 1201) and dem.heights.dtype == np.float32
    assert dem.voids == 21 and dem.filled
    assert not np.isnan(dem.heights).any()
    assert -10 < dem.heights.min() and dem.heights.max() < 1900
    g = dem.georef
    assert g["crs"] == "EPSG:4326" and g["known"]
    assert (g["origin_x"], g["origin_y"]) == (-72.0, -28.0)
    dx, dy = dem.cell_size_m
    assert 80 < dx < 95 and 90 < dy < 93
    assert dem.files == [str(TILE)]
    with pytest.raises(ValueError):
        dem.heights[0, 0] = 1.0  # read-only


def test_read_unfilled_keeps_voids_and_bitree_refuses_them():
    raw = cota.read(str(TILE), fill=False)
    assert int(np.isnan(raw.heights).sum()) == raw.voids == 21
    with pytest.raises(cota.MeshError, match="void"):
        raw.bitree()


def test_read_errors_name_the_file(tmp_path):
    with pytest.raises(cota.ReadError, match="nope.hgt"):
        cota.read(tmp_path / "nope.hgt")
    bad = tmp_path / "N00E000.hgt"
    bad.write_bytes(b"\x00" * 1001)
    with pytest.raises(cota.ReadError, match="N00E000.hgt"):
        cota.read([bad])
    with pytest.raises(cota.CotaError):
        cota.read([])


# --- meshing and proving -------------------------------------------------------------------


@pytest.mark.parametrize("bound", [1.0, 5.0, 20.0])
def test_extract_is_proved_at_every_sample(tree, bound):
    mesh = tree.extract(max_error=bound)
    report = tree.check(mesh, bound)  # coverage, no T-junction, |dz| <= bound at every sample
    assert report["max_error_m"] <= bound and report["uncovered"] == 0
    assert report["samples"] == 1201 * 1201
    assert report == tree.metrics(mesh)
    v, t = mesh.vertices, mesh.triangles
    assert v.shape == (mesh.vertex_count, 3) and v.dtype == np.float64
    assert t.shape == (mesh.triangle_count, 3) and t.dtype == np.uint32
    assert len(mesh) == mesh.triangle_count and t.max() < len(v)
    # every vertex carries its sample's height, exactly
    cols, rows = v[:, 0].astype(int), v[:, 1].astype(int)
    assert np.array_equal(v[:, 2], tree.heights[rows, cols].astype(np.float64))


def test_tin_has_fewer_triangles_and_is_proved(dem):
    crop = np.array(dem.heights[600:857, 900:1157])
    tree = cota.Bitree(crop)
    for bound in (1.0, 5.0):
        bitree_mesh = tree.extract(max_error=bound)
        tin = tree.extract(max_error=bound, tin=True)
        assert 1000 < tin.triangle_count < bitree_mesh.triangle_count
        # the TIN's exact ties may read bound + 1e-13 in f64 (ARCHITECTURE.md, TIN)
        assert tree.check(tin, bound)["max_error_m"] <= bound + 1e-9
    worst, all_covered = rasterized_max_error(crop.astype(np.float64), tin)
    assert all_covered and worst <= 5.0 + 1e-6
    budget = tree.extract(max_triangles=3000, tin=True)
    assert budget.triangle_count <= 3000
    tree.check(budget, budget.threshold_m)


def test_budget(tree):
    mesh = tree.extract(max_triangles=20000)
    assert 0 < mesh.triangle_count <= 20000
    assert tree.check(mesh, mesh.threshold_m)["max_error_m"] <= mesh.threshold_m
    finer = tree.extract(max_error=mesh.threshold_m)
    assert same_mesh(mesh, finer)


def test_check_catches_a_violated_bound(tree):
    coarse = tree.extract(max_error=50.0)
    with pytest.raises(cota.CheckError, match="violation"):
        tree.check(coarse, 1.0)


def rasterized_max_error(heights, mesh):
    """Independent of cota's checker: the largest |plane - height| over every sample
    in or on each triangle (barycentric coordinates, numpy), and the samples covered."""
    v, t = mesh.vertices, mesh.triangles.astype(np.int64)
    worst, covered = 0.0, np.zeros(heights.shape, bool)
    for a, b, c in t:
        (xa, ya, za), (xb, yb, zb), (xc, yc, zc) = v[a], v[b], v[c]
        x0, x1 = int(min(xa, xb, xc)), int(max(xa, xb, xc))
        y0, y1 = int(min(ya, yb, yc)), int(max(ya, yb, yc))
        ys, xs = np.mgrid[y0 : y1 + 1, x0 : x1 + 1]
        d = (yb - yc) * (xa - xc) + (xc - xb) * (ya - yc)
        la = ((yb - yc) * (xs - xc) + (xc - xb) * (ys - yc)) / d
        lb = ((yc - ya) * (xs - xc) + (xa - xc) * (ys - yc)) / d
        lc = 1 - la - lb
        inside = (la >= -1e-9) & (lb >= -1e-9) & (lc >= -1e-9)
        z = la * za + lb * zb + lc * zc
        err = np.abs(z - heights[ys, xs])[inside]
        worst = max(worst, float(err.max()))
        covered[ys[inside], xs[inside]] = True
    return worst, bool(covered.all())


def test_independent_rasterizer_agrees(dem):
    crop = np.array(dem.heights[600:729, 900:1029])  # 129 x 129, 1000+ m of relief
    tree = cota.Bitree(crop, cell_size_m=90.0)
    for bound in (2.0, 10.0):
        mesh = tree.extract(max_error=bound)
        assert mesh.triangle_count > 1000  # rough terrain: not a trivial mesh
        worst, all_covered = rasterized_max_error(crop.astype(np.float64), mesh)
        assert all_covered
        assert bound / 2 < worst <= bound + 1e-6
        assert abs(worst - tree.metrics(mesh)["max_error_m"]) < 1e-6


def test_foreign_arrays_are_measured_and_checked(tree):
    mesh = tree.extract(max_error=5.0)
    again = tree.mesh_from_arrays(mesh.vertices[:, :2].astype(np.uint16), mesh.triangles)
    assert same_mesh(mesh, again)
    assert tree.metrics(again) == tree.check(again, 5.0)
    clockwise = tree.mesh_from_arrays(mesh.vertices, mesh.triangles[:, ::-1])
    with pytest.raises(cota.CheckError, match="clockwise"):
        tree.check(clockwise, 5.0)
    assert tree.metrics(clockwise) == tree.metrics(mesh)  # the metrics need no orientation
    with pytest.raises(ValueError, match="vertex 0"):
        tree.mesh_from_arrays([[0.5, 0.0]], [[0, 0, 0]])
    with pytest.raises(ValueError, match="vertex 1"):
        tree.mesh_from_arrays([[0, 0], [1201, 0]], [[0, 1, 0]])
    with pytest.raises(ValueError, match="triangle 0"):
        tree.mesh_from_arrays([[0, 0], [1, 0], [0, 1]], [[0, 1, 3]])


# --- numpy round trips -----------------------------------------------------------------------


def test_numpy_round_trip_matches_the_dem(dem, tree):
    from_numpy = cota.Bitree(dem.heights, cell_size_m=90.0)
    assert np.array_equal(from_numpy.heights, dem.heights)
    for bound in (2.0, 10.0):
        assert same_mesh(from_numpy.extract(max_error=bound), tree.extract(max_error=bound))


def test_dtypes_and_nodata_agree():
    raw = cota.read(TILE, fill=False).heights  # int-valued float32 with NaN voids
    as_f32 = cota.Bitree(raw)
    as_f64 = cota.Bitree(raw.astype(np.float64))
    as_i16 = cota.Bitree(np.nan_to_num(raw, nan=-32768).astype(np.int16), nodata=-32768)
    assert as_f32.voids_filled == as_f64.voids_filled == as_i16.voids_filled == 21
    ref = as_f32.extract(max_error=5.0)
    assert same_mesh(ref, as_f64.extract(max_error=5.0))
    assert same_mesh(ref, as_i16.extract(max_error=5.0))
    as_f32.check(ref, 5.0)
    with pytest.raises(cota.MeshError, match="void"):
        cota.Bitree(raw, voids="refuse")


def test_non_contiguous_arrays_are_read_in_logical_order(dem):
    h = dem.heights[600:1000, 800:1100]
    flipped = h[::-1, ::2]
    assert not flipped.flags.c_contiguous
    a = cota.Bitree(flipped).extract(max_error=3.0)
    assert a.triangle_count > 1000
    b = cota.Bitree(np.ascontiguousarray(flipped)).extract(max_error=3.0)
    assert same_mesh(a, b)
    fortran = np.asfortranarray(h)
    assert same_mesh(
        cota.Bitree(fortran).extract(max_error=3.0), cota.Bitree(np.array(h)).extract(max_error=3.0)
    )


# --- bad arrays and requests: clean exceptions, never a crash ----------------------------------


@pytest.mark.parametrize(
    "arr, exc, match",
    [
        (np.zeros(10, np.float32), ValueError, "2-D"),
        (np.zeros((4, 4, 2), np.float32), ValueError, "2-D"),
        (np.zeros((0, 5), np.float32), ValueError, "non-empty"),
        (np.zeros((5, 0), np.float64), ValueError, "non-empty"),
        (np.full((8, 8), np.nan, np.float32), cota.MeshError, "void"),
        (np.zeros((8, 8), np.int32), TypeError, "int32"),
        (np.zeros((8, 8), np.uint16), TypeError, "uint16"),
        (np.zeros((8, 8), np.complex64), TypeError, "complex64"),
        (np.zeros((8, 8), ">f4"), TypeError, ">f4"),
        ([[1.0, 2.0], [3.0, 4.0]], TypeError, "list"),
        (np.array([[1.0, np.inf], [3.0, 4.0]]), ValueError, "infinite|inf"),
        (np.zeros((1, 1), np.float32), cota.MeshError, "2x2"),
    ],
)
def test_bad_arrays(arr, exc, match):
    with pytest.raises(exc, match=match):
        cota.Bitree(arr)


def test_bad_requests(tree):
    with pytest.raises(ValueError, match="exactly one"):
        tree.extract()
    with pytest.raises(ValueError, match="exactly one"):
        tree.extract(max_error=1.0, max_triangles=10)
    with pytest.raises(cota.MeshError, match="maximum error"):
        tree.extract(max_error=-1.0)
    with pytest.raises(cota.MeshError, match="budget"):
        tree.extract(max_triangles=1)
    with pytest.raises(ValueError, match="cell_size_m"):
        cota.Bitree(np.zeros((4, 4), np.float32), cell_size_m=0.0)
    with pytest.raises(ValueError, match="voids"):
        cota.Bitree(np.zeros((4, 4), np.float32), voids="ignore")
    small = cota.Bitree(np.zeros((9, 9), np.float32)).extract(max_error=1.0)
    with pytest.raises(ValueError, match="9x9"):
        tree.check(small, 1.0)


# --- writing ---------------------------------------------------------------------------------


def test_write_formats(tree, tmp_path):
    mesh = tree.extract(max_error=10.0)
    for name in ("m.glb", "m.obj", "m.ply", "m.stl"):
        mesh.write(tmp_path / name)
        assert (tmp_path / name).stat().st_size > 0
    assert (tmp_path / "m.glb").read_bytes()[:4] == b"glTF"
    mesh.write(str(tmp_path / "q.glb"), quantize=True, coords="grid")
    assert (tmp_path / "q.glb").stat().st_size < (tmp_path / "m.glb").stat().st_size
    obj = (tmp_path / "m.obj").read_text().splitlines()
    assert sum(line.startswith("f ") for line in obj) == mesh.triangle_count


def test_write_errors_leave_nothing(tree, tmp_path):
    mesh = tree.extract(max_error=10.0)
    with pytest.raises(cota.WriteError, match="xyz"):
        mesh.write(tmp_path / "m.xyz")
    with pytest.raises(cota.WriteError, match="missing"):
        mesh.write(tmp_path / "missing" / "m.glb")
    with pytest.raises(ValueError, match="coords"):
        mesh.write(tmp_path / "m.glb", coords="utm")
    assert list(tmp_path.iterdir()) == []


# --- the GIL -------------------------------------------------------------------------------


def test_long_calls_release_the_gil(dem):
    """A Python thread keeps running while cota builds and extracts. A call holding the
    GIL would freeze it for the call's whole length (pickle.dumps of a big list: the
    largest gap is 98 % of the call; here it was 4 %)."""
    import threading
    import time

    stamps, stop = [], threading.Event()

    def spin():
        n = 0
        while not stop.is_set():
            n += 1
            if n % 500 == 0:
                stamps.append(time.perf_counter())

    t = threading.Thread(target=spin)
    t.start()
    try:
        time.sleep(0.05)
        t0 = time.perf_counter()
        cota.Bitree(dem.heights).extract(max_error=1.0, tin=True)
        t1 = time.perf_counter()
    finally:
        stop.set()
        t.join()
    seen = [t0] + [s for s in stamps if t0 < s < t1] + [t1]
    largest_gap = max(b - a for a, b in zip(seen, seen[1:]))
    assert largest_gap < 0.5 * (t1 - t0)
