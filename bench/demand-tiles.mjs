// Tiles made on demand by `cota serve` (no --tiles): every tile of the
// layer requested twice over loopback, 8 at a time; the first pass makes
// each tile (cut, encode, decode, check, gzip), the second is answered from
// memory. Prints the server's preparation time and per-request latencies.
// Usage: node bench/demand-tiles.mjs [FILE...]   (default: the 2-tile mosaic
// ../shared/data/srtm/N00E010.hgt + N00E011.hgt.zip; COTA_BIN: the binary,
// default target/release/cota). Needs only node ≥ 18 (global fetch).
import { spawn } from 'node:child_process';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const repo = resolve(dirname(fileURLToPath(import.meta.url)), '..');
const bin = process.env.COTA_BIN || join(repo, 'target/release/cota');
const files = process.argv.slice(2).length
  ? process.argv.slice(2)
  : ['srtm/N00E010.hgt', 'srtm/N00E011.hgt.zip'].map((f) => join(repo, '../shared/data', f));

function serve() {
  const p = spawn(bin, ['serve', ...files, '--addr', '127.0.0.1:0'], { stdio: ['ignore', 'pipe', 'inherit'] });
  let out = '';
  return new Promise((ok, fail) => {
    p.on('exit', (c) => fail(new Error(`cota serve exited ${c}: ${out}`)));
    p.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/listening\s+(http:\/\/[^/\s]+)/);
      if (m) ok({ p, url: m[1], out });
    });
  });
}

const pct = (xs, q) => xs[Math.min(xs.length - 1, Math.floor(q * xs.length))];

async function pass(url, ids) {
  const ms = [];
  let next = 0;
  const t0 = performance.now();
  const worker = async () => {
    while (next < ids.length) {
      const [z, x, y] = ids[next++];
      const t = performance.now();
      const r = await fetch(`${url}/tiles/${z}/${x}/${y}.terrain`);
      await r.arrayBuffer();
      if (r.status !== 200) throw new Error(`${z}/${x}/${y}: ${r.status}`);
      ms.push(performance.now() - t);
    }
  };
  await Promise.all(Array.from({ length: 8 }, worker));
  ms.sort((a, b) => a - b);
  return { s: (performance.now() - t0) / 1000, p50: pct(ms, 0.5), p99: pct(ms, 0.99) };
}

const s = await serve();
try {
  const layer = await (await fetch(`${s.url}/tiles/layer.json`)).json();
  const ids = [];
  layer.available.forEach((ranges, z) => {
    for (const r of ranges) for (let x = r.startX; x <= r.endX; x++) for (let y = r.startY; y <= r.endY; y++) ids.push([z, x, y]);
  });
  console.log(s.out.split('\n').find((l) => l.startsWith('tiles')));
  for (const name of ['made on demand', 'kept']) {
    const r = await pass(s.url, ids);
    console.log(`${name}: ${ids.length} tiles in ${r.s.toFixed(2)} s, p50 ${r.p50.toFixed(2)} ms, p99 ${r.p99.toFixed(2)} ms`);
  }
} finally {
  s.p.kill('SIGTERM');
}
