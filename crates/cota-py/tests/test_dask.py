"""Sharded pyramids from Python (issue 20): ``cota.tiles`` with ``shard=`` and
``tiles_reduce`` equal one ``cota.tiles`` run byte for byte (and the ``cota`` CLI's
output when the binary is built), and ``cota.dask.build_pyramid`` on a
``LocalCluster(n_workers=2, processes=True)`` gives the same directory; it resumes
(finished shards skipped). Skipped, visibly, when dask.distributed is not installed."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

import cota

ROOT = Path(__file__).resolve().parents[3]
TILE = ROOT / "fixtures" / "S29W072.hgt.zip"
SETTINGS = {"max_zoom": 8, "normals": True, "metadata": True}


def files(d: Path) -> dict:
    return {p.relative_to(d): p.read_bytes() for p in d.rglob("*") if p.is_file()}


def same(got: dict, want: dict) -> bool:
    """``got == want``, or an AssertionError naming the files that differ (not
    pytest's dump of every tile's bytes)."""
    extra = sorted(str(k) for k in got.keys() - want.keys())
    missing = sorted(str(k) for k in want.keys() - got.keys())
    differ = sorted(str(k) for k in got.keys() & want.keys() if got[k] != want[k])
    assert not (extra or missing or differ), (
        f"{len(extra)} extra {extra[:8]}, {len(missing)} missing {missing[:8]}, "
        f"{len(differ)} differ {differ[:8]}")
    return True


def cli_exe():
    """The ``cota`` binary built last (release or debug), or None."""
    built = [p for p in (ROOT / "target/release/cota", ROOT / "target/debug/cota") if p.is_file()]
    return max(built, key=lambda p: p.stat().st_mtime, default=None)


@pytest.fixture(scope="module")
def plain(tmp_path_factory):
    out = tmp_path_factory.mktemp("plain") / "t"
    r = cota.tiles(TILE, out, **SETTINGS)
    assert r["written"] == r["tiles"] > 5
    return files(out)


def test_plain_equals_cli(plain, tmp_path):
    exe = cli_exe()
    if exe is None:
        pytest.skip("the cota binary is not built")
    out = tmp_path / "cli"
    subprocess.run([exe, "tiles", TILE, "--max-zoom", "8", "--normals", "--metadata", "-o", out], check=True,
                   capture_output=True)
    assert same(files(out), plain)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_shards_and_reduce_equal_plain(plain, tmp_path, n):
    plan = cota.tiles_plan(TILE, n, max_zoom=8)
    assert sum(p["tiles"] for p in plan) == len(plain) - 2  # but layer.json and .cota-tiles.json
    for i in range(n):
        cota.tiles(TILE, tmp_path, shard=(i, n), **SETTINGS)
        assert os.path.exists(cota.shard_record(tmp_path, i, n))
    again = cota.tiles(TILE, tmp_path, shard=(0, n), **SETTINGS)
    assert again["written"] == 0 and again["skipped"] == plan[0]["tiles"]
    assert cota.tiles_reduce(tmp_path, n) == len(plain) - 2
    assert same(files(tmp_path), plain)


def test_reduce_with_a_shard_missing_is_refused(tmp_path):
    cota.tiles(TILE, tmp_path, shard=(1, 2), **SETTINGS)
    with pytest.raises(cota.WriteError, match="missing shard"):
        cota.tiles_reduce(tmp_path, 2)
    with pytest.raises(ValueError):
        cota.tiles(TILE, tmp_path, shard=(2, 2), **SETTINGS)


def test_dask_local_cluster_equals_plain(plain, tmp_path):
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed")
    import cota.dask

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        out = tmp_path / "dask"
        r = cota.dask.build_pyramid(TILE, out, client=client, shards=3, **SETTINGS)
        assert r["plan_step"] == "ran" and r["files_read"] == {i: [str(TILE)] for i in range(3)}
        assert r["shards"] == 3 and r["skipped_shards"] == 0
        assert r["tiles"] == len(plain) - 2 and 0 < r["coarse_tiles"] < r["tiles"]
        assert same(files(out), plain)
        # Resume: two shards done (their records present), one not; only it runs.
        resumed = tmp_path / "resumed"
        for i in (0, 2):
            cota.tiles(TILE, resumed, shard=(i, 3), **SETTINGS)
        r = cota.dask.build_pyramid(TILE, resumed, client=client, shards=3, **SETTINGS)
        assert r["skipped_shards"] == 2 and list(r["files_read"]) == [1]
        assert same(files(resumed), plain)
        # Resume after the plan step: its frame is there, so it is not run again.
        again = tmp_path / "again"
        cota.tiles_plan_step(TILE, again, 3, **SETTINGS)
        r = cota.dask.build_pyramid(TILE, again, client=client, shards=3, **SETTINGS)
        assert r["plan_step"] == "skipped" and r["skipped_shards"] == 0
        assert same(files(again), plain)
    shutil.rmtree(tmp_path, ignore_errors=True)


def test_dask_worker_killed_mid_shard_gives_identical_output(tmp_path):
    """A worker process SIGKILLed while it runs a shard: the nanny restarts it, Dask
    reruns the lost task, the shard skips the tiles already complete, and the reduce
    removes the killed write's temporary file: the directory equals a plain run."""
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed")
    import signal
    import threading
    import time

    import cota.dask

    heavy = {"tile_cells": 16, "check": True}  # about 2 s per shard of 2 here
    plain = tmp_path / "plain"
    cota.tiles(TILE, plain, **heavy)
    want = files(plain)
    out = tmp_path / "killed"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        pids = client.run(os.getpid)
        result = {}
        run = threading.Thread(target=lambda: result.update(
            cota.dask.build_pyramid(TILE, out, client=client, shards=2, **heavy)))
        run.start()
        killed = None
        deadline = time.monotonic() + 60
        while killed is None and run.is_alive() and time.monotonic() < deadline:
            for addr, keys in client.processing().items():
                # Kill once the shard has begun writing tiles.
                if any(str(k).startswith("cota-shard") for k in keys) and len(list(out.rglob("*.terrain"))) > 50:
                    print("killing", addr, "with", len(list(out.rglob("*.terrain"))), "tiles written", flush=True)
                    os.kill(pids[addr], signal.SIGKILL)
                    killed = addr
                    break
            time.sleep(0.01)
        run.join(timeout=300)
    assert killed is not None, "no worker was caught running a shard (the run ended first)"
    assert result["tiles"] == len(want) - 2
    assert same(files(out), want)


SHARED = Path(os.environ.get("COTA_SHARED_DATA", ROOT.parent / "shared" / "data"))
PAIR = ("srtm/N00E010.hgt", "srtm/N00E011.hgt.zip")
PAIR_SETTINGS = {"max_zoom": 10}


@pytest.fixture()
def pair(tmp_path):
    """The two-tile mosaic copied into ``tmp_path`` (west, east), and its plain pyramid's files."""
    if not all((SHARED / p).is_file() for p in PAIR):
        pytest.skip(f"the shared data ({SHARED}) is not there")
    west, east = (tmp_path / Path(p).name for p in PAIR)
    for src, dst in zip(PAIR, (west, east)):
        shutil.copy(SHARED / src, dst)
    plain = tmp_path / "plain"
    cota.tiles([west, east], plain, **PAIR_SETTINGS)
    return west, east, files(plain)


def test_shard_after_the_plan_step_reads_only_its_part(pair, tmp_path):
    """As ``cota tiles --shard`` after ``--plan``: the westmost of 4 shards runs with the
    eastern file gone; the eastern one without it names it; the pyramid is byte-identical."""
    west, east, plain = pair
    out = tmp_path / "sharded"
    step = cota.tiles_plan_step([west, east], out, 4, **PAIR_SETTINGS)
    assert [f for f, _ in step["files"]] == [str(west), str(east)]
    assert os.path.exists(cota.shard_frame(out, 4))
    hidden = tmp_path / "elsewhere.zip"
    east.rename(hidden)
    r = cota.tiles([west, east], out, shard=(0, 4), **PAIR_SETTINGS)
    assert r["files_read"] == [str(west)] and r["written"] > 0
    with pytest.raises(cota.ReadError, match="N00E011"):
        cota.tiles([west, east], out, shard=(3, 4), **PAIR_SETTINGS)
    hidden.rename(east)
    with pytest.raises(cota.WriteError, match="other settings"):
        cota.tiles([west, east], out, shard=(1, 4), max_zoom=9)
    for i in range(1, 4):
        cota.tiles([west, east], out, shard=(i, 4), **PAIR_SETTINGS)
    cota.tiles_reduce(out, 4)
    assert same(files(out), plain)


def test_the_cli_and_python_take_each_others_plan_and_shards(pair, tmp_path):
    """One tiling job (``cota_tiles::job``) behind both: the plan step's layout
    and a plan part written by Python, the merge by ``cota tiles --plan``, two shards by
    Python and two by ``cota tiles --shard``, the reduce by Python: byte-identical to the
    plain pyramid. A frame of other settings is refused by either."""
    exe = cli_exe()
    if exe is None:
        pytest.skip("the cota binary is not built")
    west, east, plain = pair
    out = tmp_path / "mixed"
    cli = [exe, "tiles", west, east, "-o", out, "--max-zoom", "10", "--quiet"]
    assert cota.tiles_plan_layout([west, east], out, 4, **PAIR_SETTINGS)["streamed"]
    cota.tiles_plan_part([west, east], out, 4, 1, **PAIR_SETTINGS)
    subprocess.run(cli + ["--plan", "--shards", "4"], check=True, capture_output=True)
    assert os.path.exists(cota.shard_frame(out, 4))
    for i in (0, 2):
        cota.tiles([west, east], out, shard=(i, 4), **PAIR_SETTINGS)
    for i in (1, 3):
        subprocess.run(cli + ["--shard", f"{i}/4"], check=True, capture_output=True)
    other = subprocess.run([exe, "tiles", west, east, "-o", out, "--max-zoom", "9", "--shard", "1/4"],
                           capture_output=True, text=True)
    assert other.returncode != 0 and "other settings" in other.stderr, other.stderr
    cota.tiles_reduce(out, 4)
    assert same(files(out), plain)


def test_dask_shards_read_only_their_part(pair, tmp_path):
    """Under Dask the plan step runs as the first task and each shard reads only the
    input files of its part: the westmost reads only the western file, the eastmost
    only the eastern one; the result equals the plain pyramid byte for byte."""
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed")
    import cota.dask

    west, east, plain = pair
    out = tmp_path / "dask"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        r = cota.dask.build_pyramid([west, east], out, client=client, shards=4, **PAIR_SETTINGS)
    assert r["plan_step"] == "ran" and r["plan_parts"] == 4, r
    assert r["files_read"][0] == [str(west)] and r["files_read"][3] == [str(east)], r
    assert same(files(out), plain)


def test_plan_step_in_parts_equals_plain(pair, tmp_path):
    """The plan step in parts: the layout, the westmost plan part with the eastern file
    gone, a part run again skipped, the merge computing the part left; the frame and
    band corners are the plan step's in turn, and the pyramid is byte-identical."""
    west, east, plain = pair
    whole, out = tmp_path / "whole", tmp_path / "parts"
    cota.tiles_plan_step([west, east], whole, 4, **PAIR_SETTINGS)
    lay = cota.tiles_plan_layout([west, east], out, 4, **PAIR_SETTINGS)
    assert lay == {"streamed": True, "files": 2}
    hidden = tmp_path / "elsewhere.zip"
    east.rename(hidden)
    r = cota.tiles_plan_part([west, east], out, 4, 0, **PAIR_SETTINGS)
    assert r == {"streamed": True, "skipped": False, "files_read": [str(west)]}
    hidden.rename(east)
    assert cota.tiles_plan_part([west, east], out, 4, 0, **PAIR_SETTINGS)["skipped"]
    cota.tiles_plan_part([west, east], out, 4, 2, **PAIR_SETTINGS)
    with pytest.raises(ValueError, match="part < 4"):
        cota.tiles_plan_part([west, east], out, 4, 4, **PAIR_SETTINGS)
    with pytest.raises(cota.WriteError, match="other settings"):
        cota.tiles_plan_part([west, east], out, 4, 1, max_zoom=9)
    cota.tiles_plan_step([west, east], out, 4, **PAIR_SETTINGS)
    for name in (".cota-shards-4.json", ".cota-shards-4.corners"):
        assert (out / name).read_bytes() == (whole / name).read_bytes(), name
    assert not (out / ".cota-layout-4.json").exists()
    assert cota.tiles_plan_part([west, east], out, 4, 1, **PAIR_SETTINGS)["skipped"]
    for i in range(4):
        cota.tiles([west, east], out, shard=(i, 4), **PAIR_SETTINGS)
    cota.tiles_reduce(out, 4)
    assert same(files(out), plain)
    single = cota.tiles_plan_layout(west, tmp_path / "single", 2, **PAIR_SETTINGS)
    assert single == {"streamed": False, "files": 0}


def test_shards_across_the_antimeridian_name_tile_addresses(tmp_path):
    """The pair relabelled N00E179 + N00W180: ``tiles_plan``'s ranges are tile addresses
    (columns on both sides of 180 degrees, none past the world's last) that hold every
    tile written, and 3 shards with the reduce give the plain pyramid byte for byte."""
    if not all((SHARED / p).is_file() for p in PAIR):
        pytest.skip(f"the shared data ({SHARED}) is not there")
    e179, w180 = tmp_path / "N00E179.hgt", tmp_path / "N00W180.hgt.zip"
    for src, dst in zip(PAIR, (e179, w180)):
        shutil.copy(SHARED / src, dst)
    settings = {"max_zoom": 7}
    plain = tmp_path / "plain"
    cota.tiles([e179, w180], plain, **settings)
    want = files(plain)
    plan = cota.tiles_plan([e179, w180], 3, **settings)
    ranges = [r for p in plan for r in p["ranges"]]
    assert all(x0 <= x1 < 2 << z and y0 <= y1 < 1 << z for z, x0, x1, y0, y1 in ranges), ranges
    named = {Path(str(z), str(x), f"{y}.terrain")
             for z, x0, x1, y0, y1 in ranges for x in range(x0, x1 + 1) for y in range(y0, y1 + 1)}
    tiles = {k for k in want if k.suffix == ".terrain"}
    assert tiles <= named and sum(p["tiles"] for p in plan) == len(tiles)
    columns = {int(k.parts[1]) for k in tiles if k.parts[0] == "7"}
    assert 0 in columns and (2 << 7) - 1 in columns, sorted(columns)
    out = tmp_path / "sharded"
    for i in range(3):
        cota.tiles([e179, w180], out, shard=(i, 3), **settings)
    cota.tiles_reduce(out, 3)
    assert same(files(out), want)


def test_archives_and_3d_tiles_from_python(tmp_path):
    """``cota.tiles`` writes what ``cota tiles`` does through the same writer: an
    ``.mbtiles`` holding the directory's tiles, 3D Tiles terrain, and a ``.3tz``
    holding the 3D Tiles directory's files (the CLI's archive byte for byte when the
    binary is built); settings a format cannot hold raise ValueError before any work."""
    import sqlite3
    import zipfile

    opts = {"max_zoom": 6}
    plain, mb = tmp_path / "qm", tmp_path / "t.mbtiles"
    r = cota.tiles(TILE, plain, **opts)
    assert cota.tiles(TILE, mb, **opts)["written"] == r["written"] > 5
    with sqlite3.connect(mb) as db:
        rows = {(z, x, y): bytes(d)
                for z, x, y, d in db.execute("select zoom_level, tile_column, tile_row, tile_data from tiles")}
    tiles = {p.relative_to(plain) for p in plain.rglob("*.terrain")}
    assert len(rows) == len(tiles)
    for (z, x, y), d in rows.items():
        assert (plain / str(z) / str(x) / f"{y}.terrain").read_bytes() == d
    t3d, tz = tmp_path / "t3d", tmp_path / "t.3tz"
    cota.tiles(TILE, t3d, format="3dtiles", meshopt=True, **opts)
    cota.tiles(TILE, tz, format="3dtiles", meshopt=True, **opts)
    assert (t3d / "tileset.json").is_file() and not (tmp_path / "t.3tz.parts").exists()
    with zipfile.ZipFile(tz) as z:
        names = z.namelist()
        assert names[0] == "tileset.json" and names[-1] == "@3dtilesIndex1@"
        want = {str(p.relative_to(t3d)) for p in t3d.rglob("*") if p.is_file() and not p.name.startswith(".")}
        assert set(names[:-1]) == want
        assert all(z.read(n) == (t3d / n).read_bytes() for n in want)
    exe = cli_exe()
    if exe is not None:
        cli = tmp_path / "cli.3tz"
        subprocess.run([exe, "tiles", TILE, "--format", "3dtiles", "--meshopt", "--max-zoom", "6", "-o", cli],
                       check=True, capture_output=True)
        assert cli.read_bytes() == tz.read_bytes()
    for bad in ({"format": "3dtiles", "gzip": True}, {"format": "x"}, {"meshopt": True},
                {"format": "3dtiles", "out": tmp_path / "a.mbtiles"}, {"out": tmp_path / "a.3tz"}):
        out = bad.pop("out", tmp_path / "refused")
        with pytest.raises(ValueError):
            cota.tiles(TILE, out, **opts, **bad)
        assert not out.exists()


def test_tiling_keywords_are_checked_as_python_checks_them(tmp_path):
    """The tiling functions share one parser of their keywords: a misspelt one is a
    TypeError naming it, a keyword of another step is refused, a wrong type names the
    argument; nothing is written."""
    out = tmp_path / "t"
    with pytest.raises(TypeError, match="tiles\\(\\) got an unexpected keyword argument 'maxzoom'"):
        cota.tiles(TILE, out, maxzoom=6)
    with pytest.raises(TypeError, match="tiles_plan_layout\\(\\) got an unexpected keyword argument 'gzip'"):
        cota.tiles_plan_layout(TILE, out, 2, gzip=True)
    with pytest.raises(TypeError, match="argument 'max_zoom'"):
        cota.tiles(TILE, out, max_zoom="six")
    assert not out.exists()
    assert len(cota.tiles_plan(TILE, 2, max_zoom=None, min_zoom=0)) == 2
