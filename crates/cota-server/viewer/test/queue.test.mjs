// The refinement's schedule (src/queue.js) against a plain list: along a
// travel that grows by uneven steps (across high bits of the key in 1/16 m,
// where one bucket can hold most of the schedule), each frame takes out
// exactly the live entries whose key the travel has reached, each once, with
// what was pushed with them, including when the frame stops early and the
// rest is taken out in the next frames; removed and replaced entries never
// come out.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { SlackQueue } from '../src/queue.js';

test('each frame takes out exactly the live entries the travel has reached', () => {
  const nodes = 5000;
  const q = new SlackQueue(nodes);
  const want = new Map(); // node -> key of its live entry
  let seed = 7;
  const rnd = () => ((seed = (Math.imul(seed, 1664525) + 1013904223) | 0) >>> 0) / 4294967296;
  let travel = 0;
  const push = (node, key) => {
    q.push(node, key, 1 + (node & 1), node * 0.5, key, -node);
    want.set(node, key);
  };
  for (let i = 0; i < nodes; i++) if (rnd() < 0.8) push(i, rnd() < 0.1 ? 0 : rnd() ** 3 * 3000);
  let taken = 0, cutShort = 0;
  for (let frame = 0; frame < 400; frame++) {
    // Steps from 0 to 40 m, some of them exactly onto a multiple of 1/16 m.
    travel += rnd() < 0.1 ? 0 : rnd() < 0.5 ? rnd() * 40 : 1 / 16;
    const limit = frame % 7 === 3 ? 5 : Infinity;
    q.begin(travel);
    const got = [];
    let g;
    while (got.length < limit && (g = q.popDue(travel, 64)) !== 0) {
      if (g === 2) continue;
      const node = q.node;
      assert.ok(want.has(node), `node ${node} came out without a live entry`);
      const key = want.get(node);
      assert.ok(key <= travel, `node ${node} came out at travel ${travel} before its key ${key}`);
      assert.deepEqual([q.kind, q.cz, q.r, q.dT], [1 + (node & 1), node * 0.5, key, -node]);
      want.delete(node);
      got.push(node);
      // Decisions reschedule some, remove others, replace others still.
      const u = rnd();
      if (u < 0.6) push(node, travel + rnd() ** 2 * 500);
      if (u < 0.05) push((node * 7 + 1) % nodes, travel);
      if (u > 0.95) {
        const other = (node * 13 + 5) % nodes;
        q.remove(other);
        want.delete(other);
      }
    }
    taken += got.length;
    if (got.length === limit) {
      cutShort++;
      continue; // the rest waits for the next frames
    }
    const left = [...want].filter(([, k]) => k <= travel);
    assert.deepEqual(left, [], `frame ${frame}: due entries left behind`);
  }
  assert.ok(taken > 5000 && cutShort > 20, `${taken} taken out, ${cutShort} frames cut short`);
  // Crossing 2^20 / 16 m (65,536 m): most of the schedule in one bucket.
  travel = 65535.9;
  for (let i = 0; i < nodes; i++) push(i, 65536 + rnd() * 100);
  for (const t of [65536.05, 65540, 65600, 65700]) {
    q.begin(t);
    let g;
    while ((g = q.popDue(t, 64)) !== 0) {
      if (g === 1) {
        assert.ok(want.get(q.node) <= t);
        want.delete(q.node);
      }
    }
    assert.deepEqual([...want].filter(([, k]) => k <= t), []);
  }
  assert.equal(want.size, 0);
  // A key behind the travel (a step decoded after frames have run) is due at once.
  push(42, 10);
  q.begin(65700);
  assert.equal(q.popDue(65700, 64), 1);
  assert.equal(q.node, 42);
});
