// Refinement cost per frame outside the browser, as the viewer runs it: decode
// each .cstream in node, take the dataset's own cell size from the stream's
// georeference (as cota-server's meta.json does), and fly two scripted flights
// through src/lod.js with the viewer's per-frame time budget:
//   fast: approach from 0.6 × the extent to 25 cells in 60 frames (5 % closer
//         per frame at 90 m cells), a low pass of half the extent in 60 frames,
//         a climb while turning in 60 frames;
//   slow: the same path in 600 frames a leg.
// After each flight the camera stops and the bench counts the frames until the
// largest screen error over the mesh is back within the target.
//
//   node bench/refine.mjs A.cstream [B.cstream ...]
//   BUDGET_MS=4 (the viewer's budget; "inf" for none)  TARGET_PX=1
//   JSON=1 prints one JSON line per dataset and flight.
import { readFileSync } from 'node:fs';
import { basename } from 'node:path';
import { StreamReader } from '../src/decoder.js';
import { cellSizeM } from '../src/georef.js';
import { Lod, FRAME_BUDGET_MS } from '../src/lod.js';

const budgetMs = process.env.BUDGET_MS === 'inf' ? Infinity : Number(process.env.BUDGET_MS || FRAME_BUDGET_MS);
const targetPx = Number(process.env.TARGET_PX || 1);
/** Viewport 1280 × 720, vertical field of view 60°. */
const K = 720 / (2 * Math.tan(Math.PI / 6));
/** Frames the bench waits after the camera stops before calling it stuck. */
const SETTLE_LIMIT = 200;
/** Frames a leg: the fast flight is the browser test's (2 % closer a frame on
 * the approach at 90 m cells), the slow one five times slower. */
const FAST_FRAMES = 200, SLOW_FRAMES = 1000;

function load(file) {
  const bytes = new Uint8Array(readFileSync(file));
  const r = new StreamReader();
  const infos = r.push(bytes);
  r.finish();
  const d = r.decoder;
  const cell = cellSizeM(r.georef, d.w, d.h);
  const heights = new Float32Array(d.w * d.h);
  const stepOf = new Uint8Array(d.w * d.h).fill(255);
  for (const info of infos) {
    for (const i of info.points) {
      heights[i] = d.heightM(i);
      stepOf[i] = info.index;
    }
  }
  return { name: basename(file), w: d.w, h: d.h, cell, heights, stepOf, infos };
}

function newLod(ds) {
  const lod = new Lod({ width: ds.w, height: ds.h, cellX: ds.cell[0], cellY: ds.cell[1], heights: ds.heights, stepOf: ds.stepOf });
  for (const info of ds.infos) lod.addStep(info.index, info.maxErrorM, info.points);
  return lod;
}

/** The flight's eye positions, `n` frames a leg, in the viewer's centred metres. */
function flight(ds, n) {
  const ext = Math.max(ds.w * ds.cell[0], ds.h * ds.cell[1]);
  const centre = ((ds.h - 1) >> 1) * ds.w + ((ds.w - 1) >> 1);
  const zFocus = ds.heights[centre] || 0;
  const az = (-110 * Math.PI) / 180, el = (35 * Math.PI) / 180;
  const at = (dd, a, fx) => [fx + dd * Math.cos(el) * Math.cos(a), dd * Math.cos(el) * Math.sin(a), zFocus + dd * Math.sin(el)];
  const far = 0.6 * ext, near = 25 * Math.max(ds.cell[0], ds.cell[1]), pass = 0.5 * ext;
  const path = [];
  for (let k = 0; k < n; k++) path.push(at(far * (near / far) ** (k / (n - 1)), az, 0));
  for (let k = 0; k < n; k++) path.push(at(near, az, (pass * k) / (n - 1)));
  for (let k = 0; k < n; k++) path.push(at(near * (far / near) ** (k / (n - 1)), az + (k * 0.4) / n, pass));
  return path;
}

const pct = (s, q) => s[Math.min(s.length - 1, Math.floor(s.length * q))];

function fly(ds, name, n) {
  const lod = newLod(ds);
  const path = flight(ds, n);
  lod.update(path[0], K, targetPx, Infinity);
  const times = [], cpus = [];
  let cut = 0, evals = 0;
  const frame = (eye) => {
    const c = process.cpuUsage();
    const t = performance.now();
    lod.update(eye, K, targetPx, budgetMs);
    times.push(performance.now() - t);
    const dc = process.cpuUsage(c);
    cpus.push((dc.user + dc.system) / 1000);
  };
  for (const eye of path) {
    const e0 = lod.evaluations;
    frame(eye);
    if (lod.pending) cut++;
    evals += lod.evaluations - e0;
  }
  // The camera stops: frames until the screen error is within the target.
  const eye = path.at(-1);
  let settle = 0;
  let err = lod.maxScreenError().sent;
  while (err > targetPx + 1e-9 && settle < SETTLE_LIMIT) {
    frame(eye);
    settle++;
    err = lod.maxScreenError().sent;
  }
  const s = [...times].sort((a, b) => a - b);
  const c = [...cpus].sort((a, b) => a - b);
  return {
    dataset: ds.name, cell_m: ds.cell.map((c) => +c.toFixed(2)), flight: name, frames: path.length,
    budget_ms: budgetMs, median_ms: s[s.length >> 1], p90_ms: pct(s, 0.9), max_ms: s.at(-1),
    cpu_median_ms: c[c.length >> 1], cpu_p90_ms: pct(c, 0.9),
    frames_cut_by_budget: cut, evaluations_per_frame: evals / path.length,
    frames_to_target_after_stop: err <= targetPx + 1e-9 ? settle : null, screen_error_px: err, peak_triangles: lod.triCount,
  };
}

for (const file of process.argv.slice(2)) {
  const ds = load(file);
  for (const [name, n] of [['fast', FAST_FRAMES], ['slow', SLOW_FRAMES]]) {
    const r = fly(ds, name, n);
    if (process.env.JSON) {
      console.log(JSON.stringify(r));
      continue;
    }
    console.log(`${r.dataset} (cells ${r.cell_m.join(' x ')} m) ${name} flight, ${r.frames} frames, budget ${budgetMs} ms: ` +
      `wall median ${r.median_ms.toFixed(2)} ms, p90 ${r.p90_ms.toFixed(2)} ms, max ${r.max_ms.toFixed(1)} ms; ` +
      `CPU median ${r.cpu_median_ms.toFixed(2)} ms, p90 ${r.cpu_p90_ms.toFixed(2)} ms; ` +
      `${r.frames_cut_by_budget} frames cut by the budget; ${r.evaluations_per_frame.toFixed(0)} evaluations/frame; ` +
      `after the stop: ${r.frames_to_target_after_stop ?? `> ${SETTLE_LIMIT}`} frames to ≤ ${targetPx} px (${r.screen_error_px.toFixed(3)} px)`);
  }
}
