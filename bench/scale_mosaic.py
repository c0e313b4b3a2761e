"""The body of ``bench/scale-mosaic.sh`` (issue 29, item 6): the relabelled
8x8 mosaic of the shared 3" SRTM tiles, then ``cota tiles`` over it plain,
sharded (plan step, shards in turn, reduce) and through ``cota.dask``; peak
RSS per process (and per Dask task) against the part each shard holds.

usage: python bench/scale_mosaic.py SCRATCH COTA DATA   (see scale-mosaic.sh)
env:   SCALE_RUNS (plain,sharded,dask: which runs; a pyramid is compared
       with the plain one when both ran), SCALE_SHARDS, SCALE_THREADS,
       SCALE_MAX_ZOOM
"""

from __future__ import annotations

import json, os, re, shutil, subprocess, sys, threading, time, zipfile
from array import array

scratch, cota, data = sys.argv[1:4] if __name__ == "__main__" else ("", "", "")
shards = int(os.environ.get("SCALE_SHARDS", "4"))
threads = int(os.environ.get("SCALE_THREADS", str(os.cpu_count())))
max_zoom = os.environ.get("SCALE_MAX_ZOOM", "12")
runs = os.environ.get("SCALE_RUNS", "plain,sharded,dask").split(",")
MB = 1e6
rows = []
N = 1201
SOURCES = ["N00E010.hgt", "N00E011.hgt.zip", "N41E001.hgt.zip", "N42E001.hgt.zip",
           "N49E011.hgt.zip", "N50E011.hgt.zip", "S29W072.hgt.zip"]


def load(name):
    p = os.path.join(data, "srtm", name)
    if name.endswith(".zip"):
        with zipfile.ZipFile(p) as z:
            raw = z.read(z.namelist()[0])
    else:
        raw = open(p, "rb").read()
    a = array("h", raw)
    if sys.byteorder == "little":
        a.byteswap()
    if len(a) != N * N:
        sys.exit(f"{p}: expected {N}x{N} samples, found {len(a)}")
    voids = 0
    for r in range(N):  # each void: the last valid sample to its west, else the first to its east
        row = a[r * N:(r + 1) * N]
        if -32768 not in row:
            continue
        valid = [v for v in row if v != -32768]
        last = valid[0] if valid else (a[(r - 1) * N] if r else 0)
        for c in range(N):
            if row[c] == -32768:
                row[c] = last
                voids += 1
            else:
                last = row[c]
        a[r * N:(r + 1) * N] = row
    if sys.byteorder == "little":
        a.byteswap()
    return a.tobytes(), voids


def make_mosaic():
    """The 64 files N17E020 .. N10E027 in SCRATCH/mosaic, row by row."""
    mosaic = os.path.join(scratch, "mosaic")
    os.mkdir(mosaic)
    tiles = [load(n) for n in SOURCES]
    files = []
    for r, lat in enumerate(range(17, 9, -1)):
        for c, lon in enumerate(range(20, 28)):
            f = os.path.join(mosaic, f"N{lat:02d}E{lon:03d}.hgt")
            open(f, "wb").write(tiles[(3 * r + c) % 7][0])
            files.append(f)
    print(f"mosaic: 64 files of {N}², {(8 * (N - 1) + 1) ** 2:,} samples "
          f"({sum(v for _, v in tiles):,} voids filled in the 7 sources)")
    return files


def load_avg():
    return open("/proc/loadavg").read().split()[0]


def timed(label, args, env=None):
    """Runs `cota ARGS --json` under GNU time, its RSS polled every 0.2 s:
    (wall s, peak RSS bytes, last JSON line, load, [(s, RSS bytes)])."""
    tfile = os.path.join(scratch, "time.txt")
    l0 = load_avg()
    t = time.perf_counter()
    p = subprocess.Popen(["/usr/bin/time", "-v", "-o", tfile, cota, *args, "--json"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    trace = []

    def poll():
        while p.poll() is None:
            try:
                kids = open(f"/proc/{p.pid}/task/{p.pid}/children").read().split()
                st = open(f"/proc/{kids[0]}/status").read() if kids else ""
                m = re.search(r"VmRSS:\s+(\d+) kB", st)
                if m:
                    trace.append((time.perf_counter() - t, int(m[1]) * 1024))
            except OSError:
                pass
            time.sleep(0.2)

    th = threading.Thread(target=poll)
    th.start()
    stdout, stderr = p.communicate()
    wall = time.perf_counter() - t
    th.join()
    if p.returncode != 0:
        sys.exit(f"{label}: exit {p.returncode}\n{stderr}")
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", open(tfile).read())[1]) * 1024
    out = [l for l in stdout.splitlines() if l.startswith("{")]
    return wall, rss, json.loads(out[-1]) if out else {}, f"{l0}–{load_avg()}", trace


def stages(v, wall, trace):
    """Peak polled RSS in each phase of a run's report: read + resample +
    deviation (before `prepare`), prepare (the bitree, source codes and
    coarse levels), tiles."""
    sec = v.get("seconds", {})
    prep, tiles = sec.get("prepare", 0.0), sec.get("tiles", 0.0)
    t1 = sec.get("total", wall) - prep - tiles
    cuts = [("read + resample + deviation", 0, t1), ("prepare", t1, t1 + prep), ("tiles", t1 + prep, wall)]
    parts = []
    for name, a, b in cuts:
        m = max((r for s, r in trace if a <= s < b), default=0)
        parts.append(f"{name} {b - a:.1f} s, {m / 1e6:.0f} MB")
    return "; ".join(parts)


def hgt_extent(names):
    """Samples of the mosaic of the .hgt files named (their bounding block)."""
    ll = [tuple(int(x) for x in re.search(r"N(\d+)E(\d+)", os.path.basename(n)).groups()) for n in names]
    rows = max(a for a, _ in ll) - min(a for a, _ in ll) + 1
    cols = max(b for _, b in ll) - min(b for _, b in ll) + 1
    return (rows * (N - 1) + 1) * (cols * (N - 1) + 1)



def table():
    print()
    print("| run | wall (s) | tiles written | tiles/s | peak RSS (MB) | lattice points | source samples | "
          "lattice + hierarchy (MB) | peak ÷ (lattice + hierarchy) | + source (MB) | peak ÷ (+ source) | load |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for name, wall, n, rss, pts, src, load in rows:
        if pts:
            lh = 8 * pts
            ls = lh + 4 * src
            extra = f"{pts:,} | {src:,} | {lh / MB:.0f} | {rss / lh:.2f} | {ls / MB:.0f} | {rss / ls:.2f}"
        else:
            extra = "- | - | - | - | - | -"
        rate = f"{n / wall:.0f}" if n else "-"
        print(f"| {name} | {wall:.1f} | {n:,} | {rate} | {rss / MB:.0f} | {extra} | {load} |")
    sharded = [r for r in rows if r[0].startswith(("plan", "shard", "reduce"))]
    if not sharded:
        return
    tw = sum(r[1] for r in sharded)
    tn = sum(r[2] for r in sharded)
    print(f"| sharded, all in turn | {tw:.1f} | {tn:,} | {tn / tw:.0f} | {max(r[3] for r in sharded) / MB:.0f} "
          f"| - | - | - | - | - | - | - |")



def peak_plugin():
    """A worker plugin that records each task's peak RSS on a
    single-threaded worker (VmHWM, reset through clear_refs when the task
    starts)."""
    from distributed.diagnostics.plugin import WorkerPlugin

    class Peak(WorkerPlugin):
        """Per task on this single-threaded worker: its peak RSS (VmHWM,
        reset when the task starts)."""
        def setup(self, worker):
            self.peaks = {}
        def transition(self, key, start, finish, **kw):
            if finish == "executing":
                open("/proc/self/clear_refs", "w").write("5")
            elif start == "executing":
                hwm = re.search(r"VmHWM:\s+(\d+) kB", open("/proc/self/status").read())[1]
                self.peaks[str(key)] = int(hwm) * 1024
    return Peak()


def main():
    files = make_mosaic()
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    common = [*files, "--max-zoom", max_zoom]
    print(f"cota tiles --max-zoom {max_zoom}, {threads} threads on {os.cpu_count()} cores, {shards} shards")
    plain = os.path.join(scratch, "plain") if "plain" in runs else None
    if plain:
        run_plain(files, common, env, plain)
    if "sharded" in runs:
        run_sharded(common, env, plain)
    if "dask" in runs:
        run_dask(files, plain)


def same_as(plain, out):
    """Whether OUT holds the plain pyramid's files byte for byte (None
    without a plain run)."""
    if not plain:
        return None
    return subprocess.run(["diff", "-rq", plain, out], capture_output=True).returncode == 0


def run_plain(files, common, env, plain):
    """One `cota tiles` over the 64 files."""
    wall, rss, v, load, trace = timed("plain", ["tiles", *common, "-o", plain], env)
    print(f"plain, peak polled RSS per phase: {stages(v, wall, trace)}")
    w, h = v["lattice"]["window"]
    rows.append(("plain", wall, v["written"], rss, w * h, hgt_extent(files), load))
    print(f"plain: lattice {w}×{h}, {v['lattice']['cell_arcsec']}\" cells, prepare {v['seconds']['prepare']:.1f} s, "
          f"tiles {v['seconds']['tiles']:.1f} s", flush=True)


def run_sharded(common, env, plain):
    """The plan step, each shard in turn, the reduce."""
    out = os.path.join(scratch, "sharded")
    wall, rss, v, load, _ = timed("plan", ["tiles", *common, "-o", out, "--plan", "--shards", str(shards)], env)
    rows.append(("plan step", wall, 0, rss, None, None, load))
    for i in range(shards):
        wall, rss, v, load, trace = timed(f"shard {i}", ["tiles", *common, "-o", out, "--shard", f"{i}/{shards}"],
                                          env)
        print(f"shard {i}/{shards}, peak polled RSS per phase: {stages(v, wall, trace)}", flush=True)
        w, h = v["lattice"]["window"]
        rows.append((f"shard {i}/{shards}", wall, v["written"], rss, w * h, hgt_extent(v["part"]["files_read"]),
                     load))
    wall, rss, v, load, _ = timed("reduce", ["tiles", "-o", out, "--reduce", "--shards", str(shards)], env)
    rows.append(("reduce", wall, v["coarse_written"], rss, None, None, load))
    print(f"sharded pyramid identical to the plain one: {same_as(plain, out)}")
    shutil.rmtree(out)
    table()


def run_dask(files, plain):
    """cota.dask.build_pyramid on one single-threaded worker per core."""
    os.environ["RAYON_NUM_THREADS"] = "1"
    import cota.dask  # PYTHON with the cota package (e.g. via PYTHONPATH)
    import distributed

    dout = os.path.join(scratch, "dask")
    with distributed.LocalCluster(n_workers=threads, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cl, distributed.Client(cl) as client:
        client.register_plugin(peak_plugin(), name="peak")
        l0 = load_avg()
        t = time.perf_counter()
        r = cota.dask.build_pyramid(files, dout, client, shards=shards, max_zoom=int(max_zoom))
        wall = time.perf_counter() - t
        peaks = client.run(lambda dask_worker: dask_worker.plugins["peak"].peaks)
    peak = {}
    for worker in peaks.values():
        for key, b in worker.items():
            peak[key.removesuffix("-dask")] = b
    rows.append((f"dask, {threads} workers × 1 thread", wall, r["tiles"], max(peak.values()), None, None,
                 f"{l0}–{load_avg()}"))
    print("dask peak RSS per task (MB): " + ", ".join(f"{k} {b / MB:.0f}" for k, b in sorted(peak.items())))
    print(f"dask pyramid identical to the plain one: {same_as(plain, dout)}")
    table()


if __name__ == "__main__":
    main()
