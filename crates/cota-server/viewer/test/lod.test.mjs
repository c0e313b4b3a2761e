// The incremental view-dependent mesh (src/lod.js) on real data decoded by
// src/decoder.js: after every update the leaves are exactly those of the
// hierarchy split where `active` says (so conforming: no T-junction), the
// split set is closed under the diamond dependencies, every leaf faces up,
// and every leaf whose split point has arrived is within the screen-error
// target. Detail rises as the eye comes closer and falls as it leaves.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import { dirname, join } from 'node:path';
import { StreamReader, StreamDecoder } from '../src/decoder.js';
import { Lod } from '../src/lod.js';

const golden = join(dirname(fileURLToPath(import.meta.url)), 'golden');

function setup(name, steps = Infinity) {
  const bytes = new Uint8Array(readFileSync(join(golden, `${name}.cstream`)));
  const r = new StreamReader();
  const infos = [];
  for (let at = 0; at < bytes.length; at += 4096) infos.push(...r.push(bytes.subarray(at, at + 4096)));
  const d = r.decoder;
  const heights = new Float32Array(d.w * d.h);
  const stepOf = new Uint8Array(d.w * d.h).fill(255);
  const lod = new Lod({ width: d.w, height: d.h, cellX: 30, cellY: 30, heights, stepOf });
  for (const info of infos.slice(0, steps)) {
    for (const i of info.points) {
      heights[i] = d.heightM(i);
      stepOf[i] = info.index;
    }
    lod.addStep(info.index, info.maxErrorM, info.points);
  }
  return { d, lod };
}

/** Leaves of the hierarchy split where lod.active is set, as sorted triples. */
function expectedLeaves(lod, d) {
  const ref = new StreamDecoder(d.header);
  ref.split.set(lod.active.map((a) => (a ? 1 : 0)));
  const out = [];
  ref.leaves((ax, ay, bx, by, cx, cy) => out.push([ay * d.w + ax, by * d.w + bx, cy * d.w + cx].sort((p, q) => p - q).join()));
  return out.sort();
}

function checkInvariants(lod, d, K, target) {
  const have = lod.leafTriangles().map((t) => [...t].sort((p, q) => p - q).join()).sort();
  assert.deepEqual(have, expectedLeaves(lod, d), 'leaves = the hierarchy cut at the split set');
  // Closure: a split point's apexes are split (or are the square's corners).
  const s = new Int32Array(8);
  for (let i = 0; i < lod.active.length; i++) {
    if (!lod.active[i]) continue;
    const x = i % lod.w, y = (i / lod.w) | 0;
    const f = lod.diamond(x, y, s);
    const o = f & (1 << 29) ? 2 : 0;
    for (const j of [o, o + 4]) {
      if (lod.inGrid(s[j], s[j + 1]) && !lod.isCorner(s[j], s[j + 1])) {
        assert.ok(lod.active[s[j + 1] * lod.w + s[j]], `apex of ${x},${y} split`);
      }
    }
  }
  // Counter-clockwise from above, and the index buffer agrees.
  for (let slot = 0; slot < lod.triTop; slot++) {
    if (lod.triKey[slot] < 0) continue;
    const v = [0, 1, 2].map((k) => lod.index[slot * 3 + k]);
    const p = v.map((k) => [lod.position[k * 3], lod.position[k * 3 + 1]]);
    const area = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
    assert.ok(area > 0, 'counter-clockwise');
    for (let k = 0; k < 3; k++) assert.equal(lod.slotOf[lod.triSamples[slot * 3 + k]], v[k]);
  }
  const e = lod.maxScreenError();
  assert.ok(e.sent <= target + 1e-9, `max screen error ${e.sent} px within ${target} px`);
  void K;
}

test('flight: conforming, within target, detail follows the eye', () => {
  const { d, lod } = setup('s29w072-200x150-dm');
  const K = 720 / (2 * Math.tan(Math.PI / 6));
  const counts = [];
  // From far above, down to the ground, and away again.
  const path = [];
  for (let k = 0; k <= 40; k++) path.push([-3000 + 100 * k, -1500, 300000 * 0.9 ** k]);
  for (let k = 0; k <= 40; k++) path.push([1000 + 150 * k, -1500 + 60 * k, 4000 * 1.1 ** k]);
  for (const [i, eye] of path.entries()) {
    lod.update(eye, K, 1, Infinity);
    assert.equal(lod.pending, false);
    counts.push(lod.triCount);
    if (i % 8 === 0) checkInvariants(lod, d, K, 1);
  }
  checkInvariants(lod, d, K, 1);
  const peak = Math.max(...counts);
  assert.ok(peak > 3 * counts[0], `detail rises: ${counts[0]} → ${peak}`);
  assert.ok(counts[counts.length - 1] < peak / 3, `detail falls: ${peak} → ${counts.at(-1)}`);
  assert.ok(lod.merges > 0 && lod.splits > 0);
});

test('a coarser target gives fewer triangles; the prefix bounds what can be split', () => {
  const { d, lod } = setup('s29w072-129x97');
  const K = 720 / (2 * Math.tan(Math.PI / 6));
  lod.update([0, -2000, 3000], K, 1, Infinity);
  const fine = lod.triCount;
  lod.update([0, -2000, 3000], K, 8, Infinity);
  checkInvariants(lod, d, K, 8);
  assert.ok(lod.triCount < fine / 2, `${lod.triCount} < ${fine} / 2`);
  // Only the first 4 steps: the refinement stays inside what has arrived.
  const p = setup('s29w072-129x97', 4);
  p.lod.update([0, -2000, 3000], K, 1, Infinity);
  checkInvariants(p.lod, p.d, K, 1);
  for (let i = 0; i < p.lod.active.length; i++) if (p.lod.active[i]) assert.ok(p.lod.stepOf[i] < 4);
  assert.ok(p.lod.maxScreenError().all > 1, 'the cut prefix leaves error the stream has not sent');
});

test('new vertices start at their hypotenuse midpoint and reach their height', () => {
  const { lod } = setup('s29w072-129x97');
  const K = 720 / (2 * Math.tan(Math.PI / 6));
  lod.update([0, 0, 200000], K, 1, Infinity);
  lod.update([0, 0, 200000], K, 1, Infinity);
  const before = lod.triCount;
  lod.update([0, 0, 1500], K, 1, Infinity);
  let morphing = 0;
  for (let s = 0; s < lod.vertTop; s++) {
    if (lod.morph[s * 2 + 1] === lod.frame) morphing++;
  }
  assert.ok(morphing > 0 && lod.triCount > before);
  for (let f = 0; f < lod.morphFrames; f++) lod.update([0, 0, 1500], K, 1, Infinity);
  for (let i = 0; i < lod.active.length; i++) {
    if (lod.slotOf[i] >= 0) assert.equal(lod.shownZ(i), lod.z[i]);
  }
});

test('a frame budget cuts refinement short, and still frames converge to the unbudgeted mesh', () => {
  const K = 720 / (2 * Math.tan(Math.PI / 6));
  const free = setup('s29w072-200x150-dm');
  const cut = setup('s29w072-200x150-dm');
  // A plunge from far to near in one frame: far more work than the budget.
  const eyes = [[0, -1500, 300000], [500, -800, 1500]];
  free.lod.update(eyes[0], K, 1, Infinity);
  cut.lod.update(eyes[0], K, 1, Infinity);
  free.lod.update(eyes[1], K, 1, Infinity);
  assert.equal(free.lod.pending, false);
  // A budget of 0 ms stops at the first look at the clock: one small slice a frame.
  cut.lod.update(eyes[1], K, 1, 0);
  assert.equal(cut.lod.pending, true, 'the plunge is cut short by the budget');
  assert.ok(cut.lod.triCount < free.lod.triCount, `cut short: ${cut.lod.triCount} < ${free.lod.triCount} triangles`);
  let frames = 1;
  while (cut.lod.pending && frames < 100000) {
    cut.lod.update(eyes[1], K, 1, 0);
    frames++;
  }
  assert.equal(cut.lod.pending, false, `caught up after ${frames} frames`);
  assert.ok(frames > 2, `the work was spread over ${frames} frames`);
  assert.deepEqual([...cut.lod.active], [...free.lod.active], 'the same split set as without a budget');
  checkInvariants(cut.lod, cut.d, K, 1);
});

test('steps decoded after the eye has moved are refined at once', () => {
  const K = 720 / (2 * Math.tan(Math.PI / 6));
  const late = setup('s29w072-129x97', 0);
  const early = setup('s29w072-129x97');
  // Frames run (the eye travels, then stops) before the stream's first step arrives.
  for (let k = 4; k >= 0; k--) late.lod.update([1000 * k, -2000, 3000], K, 1, Infinity);
  const bytes = new Uint8Array(readFileSync(join(golden, 's29w072-129x97.cstream')));
  const r = new StreamReader();
  for (const info of r.push(bytes)) {
    for (const i of info.points) {
      late.lod.z[i] = r.decoder.heightM(i);
      late.lod.stepOf[i] = info.index;
    }
    late.lod.addStep(info.index, info.maxErrorM, info.points);
  }
  late.lod.update([0, -2000, 3000], K, 1, Infinity);
  early.lod.update([0, -2000, 3000], K, 1, Infinity);
  checkInvariants(late.lod, late.d, K, 1);
  assert.deepEqual([...late.lod.active], [...early.lod.active], 'the same split set as with the steps first');
});
