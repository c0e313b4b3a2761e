#!/usr/bin/env python3
"""Issue 31's targets for `cota serve` and the bounded readers, measured.

1. A 3601 x 3601 input: the shared 3" SRTM tile S29W072 (or the bundled
   fixture) resampled bilinearly by 3 onto the 1" layout, with seeded
   Gaussian noise of 1.5 m (a real 1" tile's sensor noise; without it the
   resampled surface is smoother than real data and its tiles cheaper),
   written as a raw S29W072.hgt in a temporary directory (never committed).
2. `cota serve` on it: time from spawn to the "listening" line and to the
   first answered /health; time until its tiles are prepared.
3. CLIENTS concurrent clients (asyncio, raw HTTP/1.1 on loopback, keep-alive)
   for SECONDS, each asking for distinct tiles of the deepest zooms (made on
   demand; once all were asked, again from the first: then from the cache,
   or made again when --cache-mib is small); a client answered 503 waits
   Retry-After (at most 1 s), as a client should. The server's RSS and
   thread count are sampled every 50 ms from /proc: the peak during the
   load, and VmHWM (the peak since start, the background encoding included). Counted: 200s, 503s with and without
   Retry-After, other statuses, broken connections.
4. Meanwhile a half-open request (headers never finished): seconds until the
   server closes it.
5. `cota info /dev/zero` and `head -c 3000000000 /dev/zero | cota info -`:
   wall time and peak RSS (wait4's ru_maxrss), exit status and message.

Usage: python3 bench/serve-load.py [--cota target/release/cota] [--clients 200]
       [--seconds 15] [--cache-mib N] [--json OUT]   (needs numpy; Linux /proc,
       /usr/bin/time for the peak memory of `cota info`)
"""
import argparse
import asyncio
import json
import os
import random
import re
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
import zipfile

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def make_input(dirname):
    """A 3601 x 3601 S29W072.hgt: the 1201 x 1201 tile resampled by 3."""
    for cand in (os.path.join(REPO, "../shared/data/srtm/S29W072.hgt.zip"),
                 os.path.join(REPO, "fixtures/S29W072.hgt.zip")):
        if os.path.exists(cand):
            src = cand
            break
    with zipfile.ZipFile(src) as z:
        name = next(n for n in z.namelist() if n.lower().endswith(".hgt"))
        a = np.frombuffer(z.read(name), dtype=">i2").reshape(1201, 1201).astype(np.float64)
    void = a == -32768
    a[void] = np.median(a[~void])
    t = np.arange(3601) / 3.0
    i0 = np.minimum(t.astype(int), 1199)
    f = t - i0
    rows = a[i0, :] * (1 - f)[:, None] + a[i0 + 1, :] * f[:, None]
    b = rows[:, i0] * (1 - f)[None, :] + rows[:, i0 + 1] * f[None, :]
    b += np.random.default_rng(31).normal(0.0, 1.5, b.shape)
    out = os.path.join(dirname, "S29W072.hgt")
    np.round(b).astype(">i2").tofile(out)
    return out, src


def proc_status(pid):
    d = {}
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                k, _, v = line.partition(":")
                if k in ("VmRSS", "VmHWM", "Threads"):
                    d[k] = int(v.split()[0])
    except OSError:
        pass
    return d


class Sampler(threading.Thread):
    def __init__(self, pid):
        super().__init__(daemon=True)
        self.pid, self.stop, self.peak_rss_kb, self.peak_threads, self.hwm_kb = pid, False, 0, 0, 0
        self.load_rss_kb, self.in_load = 0, False

    def run(self):
        while not self.stop:
            s = proc_status(self.pid)
            self.peak_rss_kb = max(self.peak_rss_kb, s.get("VmRSS", 0))
            if self.in_load:
                self.load_rss_kb = max(self.load_rss_kb, s.get("VmRSS", 0))
            self.hwm_kb = max(self.hwm_kb, s.get("VmHWM", 0))
            self.peak_threads = max(self.peak_threads, s.get("Threads", 0))
            time.sleep(0.05)


def get_json(url):
    with urllib.request.urlopen(url, timeout=10) as r:
        return json.loads(r.read())


async def read_response(reader):
    head = await reader.readuntil(b"\r\n\r\n")
    text = head.decode("latin-1")
    status = int(text[9:12])
    m = re.search(r"(?im)^content-length:\s*(\d+)", text)
    n = int(m.group(1)) if m else 0
    await reader.readexactly(n)
    retry = re.search(r"(?im)^retry-after:\s*(\d+)", text)
    return status, (int(retry.group(1)) if retry else None)


async def client(host, port, tiles, deadline, counts):
    reader = writer = None
    while time.monotonic() < deadline:
        if writer is None:
            try:
                reader, writer = await asyncio.open_connection(host, port)
            except OSError:
                counts["connect_errors"] += 1
                await asyncio.sleep(0.1)
                continue
        k = counts["next"]
        counts["next"] += 1
        z, x, y = tiles[k % len(tiles)]
        req = f"GET /tiles/{z}/{x}/{y}.terrain HTTP/1.1\r\nHost: b\r\nAccept-Encoding: gzip\r\n\r\n"
        try:
            writer.write(req.encode())
            await writer.drain()
            status, retry = await asyncio.wait_for(read_response(reader), 60)
        except (OSError, asyncio.IncompleteReadError, asyncio.TimeoutError, asyncio.LimitOverrunError):
            counts["broken"] += 1
            writer = None
            continue
        if status == 200:
            counts["200"] += 1
        elif status == 503:
            counts["503_retry_after" if retry is not None else "503_without_retry_after"] += 1
            await asyncio.sleep(min(retry or 1, 1))
        else:
            counts[str(status)] = counts.get(str(status), 0) + 1
    if writer is not None:
        writer.close()


async def half_open(host, port, limit_s=60):
    r, w = await asyncio.open_connection(host, port)
    w.write(b"GET /health HTTP/1.1\r\nHost: b\r\n")  # never finished
    await w.drain()
    t = time.monotonic()
    try:
        data = await asyncio.wait_for(r.read(), limit_s)
    except asyncio.TimeoutError:
        return None, b""
    return time.monotonic() - t, data[:40]


async def load(host, port, tiles, clients, seconds):
    counts = {"200": 0, "503_retry_after": 0, "503_without_retry_after": 0, "broken": 0, "connect_errors": 0, "next": 0}
    deadline = time.monotonic() + seconds
    ho = asyncio.ensure_future(half_open(host, port))
    t0 = time.monotonic()
    await asyncio.gather(*(client(host, port, tiles, deadline, counts) for _ in range(clients)))
    del counts["next"]
    counts["seconds"] = time.monotonic() - t0
    closed_after, said = await ho
    return counts, closed_after, said


def serve(cota, hgt, extra):
    t0 = time.monotonic()
    p = subprocess.Popen([cota, "serve", hgt, "--addr", "127.0.0.1:0", *extra], stdout=subprocess.PIPE, text=True)
    lines = []
    while True:
        line = p.stdout.readline()
        if not line:
            raise SystemExit(f"cota serve exited: {''.join(lines)}")
        lines.append(line)
        m = re.search(r"listening\s+http://([\d.]+):(\d+)/", line)
        if m:
            t_listen = time.monotonic() - t0
            break
    threading.Thread(target=lambda: [lines.append(l) for l in p.stdout], daemon=True).start()
    host, port = m.group(1), int(m.group(2))
    while True:
        try:
            get_json(f"http://{host}:{port}/health")
            break
        except OSError:
            time.sleep(0.005)
    return p, host, port, t_listen, time.monotonic() - t0, lines


def deep_tiles(layer):
    avail = layer["available"]
    out = []
    for z in range(len(avail) - 1, max(len(avail) - 3, -1), -1):
        for r in avail[z]:
            for x in range(r["startX"], r["endX"] + 1):
                for y in range(r["startY"], r["endY"] + 1):
                    out.append((z, x, y))
    random.Random(31).shuffle(out)
    return out


def refusal(cmd, stdin_cmd=None):
    """Runs `cmd` under /usr/bin/time (stdin from `stdin_cmd`): wall s, peak
    RSS MB, exit code, last stderr line. (wait4's ru_maxrss would count this
    script's own memory, which a forked child starts with.)"""
    feeder = subprocess.Popen(stdin_cmd, stdout=subprocess.PIPE) if stdin_cmd else None
    with tempfile.NamedTemporaryFile("r") as tf:
        p = subprocess.Popen(["/usr/bin/time", "-o", tf.name, "-f", "%e %M", *cmd],
                             stdin=feeder.stdout if feeder else subprocess.DEVNULL,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        if feeder:
            feeder.stdout.close()
        err = p.stderr.read().decode(errors="replace").strip().splitlines()
        code = p.wait()
        wall, kb = tf.read().split()[-2:]
    if feeder:
        feeder.kill()
        feeder.wait()
    return {"seconds": float(wall), "peak_rss_mb": round(int(kb) / 1024, 1), "exit": code,
            "message": next((l for l in err if l.startswith("cota")), "")}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cota", default=os.path.join(REPO, "target/release/cota"))
    ap.add_argument("--clients", type=int, default=200)
    ap.add_argument("--seconds", type=float, default=15)
    ap.add_argument("--cache-mib", type=int)
    ap.add_argument("--json")
    a = ap.parse_args()
    res = {}
    with tempfile.TemporaryDirectory() as d:
        hgt, src = make_input(d)
        res["input"] = f"{src} resampled x3 to 3601 x 3601 ({os.path.getsize(hgt)} bytes)"
        extra = ["--cache-mib", str(a.cache_mib)] if a.cache_mib is not None else []
        p, host, port, t_listen, t_health, lines = serve(a.cota, hgt, extra)
        sampler = Sampler(p.pid)
        sampler.start()
        res["listen_s"] = round(t_listen, 3)
        res["first_health_s"] = round(t_health, 3)
        t0 = time.monotonic()
        while get_json(f"http://{host}:{port}/health")["tiles"] == "pending":
            time.sleep(0.05)
        res["tiles_ready_s"] = round(time.monotonic() - t0 + t_health, 2)
        tiles = deep_tiles(get_json(f"http://{host}:{port}/tiles/layer.json"))
        res["distinct_deep_tiles"] = len(tiles)
        rss_before = proc_status(p.pid)
        sampler.in_load = True
        counts, closed_after, said = asyncio.run(load(host, port, tiles, a.clients, a.seconds))
        sampler.in_load = False
        h = get_json(f"http://{host}:{port}/health")
        sampler.stop = True
        sampler.join()
        res.update({
            "clients": a.clients, "load": counts, "alive_after": h["status"] == "ok",
            "server_work": h["work"], "rss_before_load_mb": round(rss_before.get("VmRSS", 0) / 1024),
            "peak_rss_during_load_mb": round(sampler.load_rss_kb / 1024),
            "peak_rss_since_start_mb": round(max(sampler.hwm_kb, sampler.peak_rss_kb) / 1024),
            "rss_after_mb": round(proc_status(p.pid).get("VmRSS", 0) / 1024),
            "peak_threads": sampler.peak_threads,
            "half_open_closed_after_s": None if closed_after is None else round(closed_after, 2),
            "half_open_answer": said.decode(errors="replace"),
        })
        p.terminate()
        p.wait(15)
        res["server_log"] = [l.rstrip() for l in lines]
    res["info_dev_zero"] = refusal([a.cota, "info", "/dev/zero"])
    res["info_stdin_3GB"] = refusal([a.cota, "info", "-"], ["head", "-c", "3000000000", "/dev/zero"])
    print(json.dumps(res, indent=2))
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(res, fh, indent=2)


if __name__ == "__main__":
    sys.exit(main())
