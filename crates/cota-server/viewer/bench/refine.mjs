// Refinement cost per frame outside the browser: decode a .cstream in node,
// fly the viewer's scripted path (test-browser/run.mjs) through src/lod.js
// and print the per-frame time. `node bench/refine.mjs FILE.cstream`
import { readFileSync } from 'node:fs';
import { StreamReader } from '../src/decoder.js';
import { Lod } from '../src/lod.js';

const bytes = new Uint8Array(readFileSync(process.argv[2]));
const t0 = performance.now();
const r = new StreamReader();
const infos = r.push(bytes);
const d = r.decoder;
console.log(`decoded ${bytes.length} bytes, ${infos.length} steps in ${(performance.now() - t0).toFixed(0)} ms`);
const heights = new Float32Array(d.w * d.h);
const stepOf = new Uint8Array(d.w * d.h).fill(255);
const cell = [92.76, 92.15];
const lod = new Lod({ width: d.w, height: d.h, cellX: cell[0], cellY: cell[1], heights, stepOf });
for (const info of infos) {
  for (const i of info.points) {
    heights[i] = d.heightM(i);
    stepOf[i] = info.index;
  }
  lod.addStep(info.index, info.maxErrorM, info.points);
}
const K = 720 / (2 * Math.tan(Math.PI / 6));
const ext = Math.max(d.w * cell[0], d.h * cell[1]);
const zFocus = heights[((d.h - 1) / 2) * d.w + (d.w - 1) / 2] || 300;
const az = (-110 * Math.PI) / 180, el = (35 * Math.PI) / 180;
const at = (dd, a, fx) => [fx + dd * Math.cos(el) * Math.cos(a), dd * Math.cos(el) * Math.sin(a), zFocus + dd * Math.sin(el)];
const path = [];
const far = 0.6 * ext, near = 2500, n = Number(process.env.FLIGHT_N || 300);
for (let k = 0; k < n; k++) path.push(at(far * (near / far) ** (k / (n - 1)), az, 0));
for (let k = 0; k < 100; k++) path.push(at(near, az, 60 * k));
for (let k = 0; k < n; k++) path.push(at(near * (far / near) ** (k / (n - 1)), az + k * 0.004, 6000));
lod.update(path[0], K, 1, Infinity);
const times = [];
const cpu0 = process.cpuUsage();
let ev = 0, sp = 0, me = 0;
for (const eye of path) {
  const e0 = lod.evaluations, s0 = lod.splits, m0 = lod.merges;
  const t = performance.now();
  lod.update(eye, K, 1, Infinity);
  times.push(performance.now() - t);
  ev += lod.evaluations - e0;
  sp += lod.splits - s0;
  me += lod.merges - m0;
}
const cpu = process.cpuUsage(cpu0);
console.log(`process CPU time per frame (mean): ${((cpu.user + cpu.system) / 1000 / times.length).toFixed(3)} ms; wall per frame (mean) ${(times.reduce((a, b) => a + b, 0) / times.length).toFixed(3)} ms`);
const s = [...times].sort((a, b) => a - b);
console.log(`frames ${times.length}: median ${s[s.length >> 1].toFixed(3)} ms, p90 ${s[Math.floor(s.length * 0.9)].toFixed(3)} ms, max ${s.at(-1).toFixed(1)} ms; per frame ${(ev / times.length).toFixed(0)} evaluations, ${(sp / times.length).toFixed(0)} splits, ${(me / times.length).toFixed(0)} merges; peak triangles ${lod.triCount}`);
