// Times @mapbox/martini and the npm `delatin` on one raw f32 grid exported by
// `cargo run --release -p cota-bench --bin export-grid -- raw NAME FILE`.
// Usage: node martini_delatin.mjs FILE WIDTH HEIGHT NAME E1,E2,... [DELATIN_MIN_E]
// Prints one tab-separated line per measurement:
//   NAME  tool  step  E  median_ms  min_ms  runs  triangles
// martini runs only on 2^k+1 squares; delatin runs at E >= DELATIN_MIN_E.
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { performance } from 'node:perf_hooks';
import { pathToFileURL } from 'node:url';

// Both packages live in $COTA_PEERS_DIR/node_modules (bench/peers-js-py.sh
// installs them): martini's `main` is a UMD build (require), delatin is an
// ES module (import).
const modules = process.env.COTA_PEERS_DIR + '/node_modules/';
const require = createRequire(modules + 'peers.js');
const MartiniMod = require('@mapbox/martini');
const Martini = MartiniMod.default ?? MartiniMod;
const { default: Delatin } = await import(pathToFileURL(modules + 'delatin/index.js').href);

const [file, w, h, name, es, dminArg] = process.argv.slice(2);
const width = Number(w), height = Number(h);
const tolerances = es.split(',').map(Number);
const delatinMin = dminArg === undefined ? 0 : Number(dminArg);
const buf = readFileSync(file);
const heights = new Float32Array(buf.buffer, buf.byteOffset, width * height);

// Median and min of `runs` timed calls (at least one, more while under ~1 s).
function time(fn) {
  const ms = [];
  let out;
  const t0 = performance.now();
  while (ms.length < 3 || (ms.length < 15 && performance.now() - t0 < 1000)) {
    const t = performance.now();
    out = fn();
    ms.push(performance.now() - t);
  }
  ms.sort((a, b) => a - b);
  return { median: ms[ms.length >> 1], min: ms[0], runs: ms.length, out };
}
const row = (tool, step, e, r, tris) =>
  console.log([name, tool, step, e, r.median.toFixed(2), r.min.toFixed(2), r.runs, tris].join('\t'));

const pow2 = width === height && Number.isInteger(Math.log2(width - 1));
if (pow2) {
  const m = time(() => new Martini(width));
  const martini = m.out;
  row('martini', 'new', '', m, '');
  const t = time(() => martini.createTile(heights));
  row('martini', 'createTile', '', t, '');
  for (const e of tolerances) {
    const r = time(() => t.out.getMesh(e));
    row('martini', 'getMesh', e, r, r.out.triangles.length / 3);
  }
}
for (const e of tolerances) {
  if (e < delatinMin) continue;
  const r = time(() => {
    const tin = new Delatin(heights, width, height);
    tin.run(e);
    return tin;
  });
  row('delatin-js', 'run', e, r, r.out.triangles.length / 3);
}
