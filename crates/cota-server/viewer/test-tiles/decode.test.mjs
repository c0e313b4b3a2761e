// Every tile of a cota pyramid, decoded by two real clients' decoders:
// @loaders.gl/terrain's QuantizedMeshLoader and @here/quantized-mesh-decoder.
// Checks that they agree, that vertices and every DEM sample in a tile are
// within the tile's bound of the DEM (plus the lattice's own deviation from
// the DEM, which `cota tiles` reports), and that same-zoom neighbours share
// their border vertices.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { parse } from '@loaders.gl/core';
import { QuantizedMeshLoader } from '@loaders.gl/terrain';
import hereModule from '@here/quantized-mesh-decoder';
import { requireEnv, layer, report, bounds, tiles, tileBuffer, rect, dem } from './common.mjs';

// The package is a UMD bundle: its decoder is the CommonJS `default` export.
const hereDecode = hereModule.default ?? hereModule;

requireEnv();
const L = layer();
const B = bounds(L);
const deviation = report().lattice.deviation_max_m;
const D = dem();

/** Decoded with both decoders; heights in metres, positions in degrees. */
async function decodeBoth(t) {
  // Each decoder gets its own copy: both decode the indices in place.
  const buf = tileBuffer(t);
  const here = hereDecode(buf.slice(0));
  const lg = await parse(buf.slice(0), QuantizedMeshLoader, { 'quantized-mesh': { bounds: [0, 0, 1, 1] } });
  const n = here.vertexData.length / 3;
  const { minHeight, maxHeight } = here.header;
  const [w, s, e, nn] = rect(t);
  const u = (i) => here.vertexData[i];
  const v = (i) => here.vertexData[i + n];
  const vert = (i) => ({
    u: u(i),
    v: v(i),
    lon: w + (u(i) / 32767) * (e - w),
    lat: s + (v(i) / 32767) * (nn - s),
    h: minHeight + (here.vertexData[i + 2 * n] / 32767) * (maxHeight - minHeight),
  });
  const verts = Array.from({ length: n }, (_, i) => vert(i));
  return { here, lg, verts, step: (maxHeight - minHeight) / 32767 };
}

const decoded = new Map();
const key = (t) => `${t.z}/${t.x}/${t.y}`;

test('both decoders read every tile alike', async () => {
  let count = 0;
  for (const t of tiles(L)) {
    const d = await decodeBoth(t);
    decoded.set(key(t), d);
    const pos = d.lg.attributes.POSITION.value;
    assert.equal(pos.length / 3, d.verts.length, `${key(t)} vertex count`);
    assert.deepEqual(Array.from(d.lg.indices.value), Array.from(d.here.triangleIndices), `${key(t)} triangles`);
    d.verts.forEach((p, i) => {
      assert.ok(Math.abs(pos[3 * i] - p.u / 32767) < 1e-6 && Math.abs(pos[3 * i + 1] - p.v / 32767) < 1e-6);
      assert.ok(Math.abs(pos[3 * i + 2] - p.h) <= 1e-3 * Math.max(1, Math.abs(p.h)), `${key(t)} height ${i}`);
    });
    count++;
  }
  assert.ok(count >= 10, `only ${count} tiles`);
});

test('vertices are within the tile bound of the DEM', () => {
  let checked = 0;
  for (const [k, d] of decoded) {
    const { maxError } = B.get(Number(k.split('/')[0]));
    for (const p of d.verts) {
      const ref = D.at(p.lon, p.lat);
      if (ref === undefined) continue;
      assert.ok(Math.abs(p.h - ref) <= maxError + deviation, `${k}: vertex at ${p.lon},${p.lat}: ${p.h} vs DEM ${ref}`);
      checked++;
    }
  }
  assert.ok(checked > 1000, `only ${checked} vertices on the DEM`);
});

/** Calls f(lon, lat, height) for every DEM sample inside the tile's rectangle. */
function demSamples(t, f) {
  const [w, s, e, n] = rect(t);
  for (const p of D.parts) {
    const k = p.n - 1;
    const c0 = Math.max(0, Math.ceil((w - p.lon) * k));
    const c1 = Math.min(k, Math.floor((e - p.lon) * k));
    const r0 = Math.max(0, Math.ceil((p.lat + 1 - n) * k));
    const r1 = Math.min(k, Math.floor((p.lat + 1 - s) * k));
    for (let r = r0; r <= r1; r++) {
      for (let c = c0; c <= c1; c++) {
        const h = p.h[r * p.n + c];
        if (h !== -32768) f(p.lon + c / k, p.lat + 1 - r / k, h);
      }
    }
  }
}

test('every DEM sample is within the tile bound plus the lattice deviation', () => {
  let checked = 0;
  for (const t of tiles(L)) {
    const d = decoded.get(key(t));
    const { maxError } = B.get(t.z);
    const tri = d.here.triangleIndices;
    // Bucket the DEM samples of the tile, then visit each triangle's box.
    const pts = [];
    demSamples(t, (lon, lat, h) => pts.push([lon, lat, h]));
    if (pts.length === 0) continue;
    const done = new Uint8Array(pts.length);
    const [w, s, e, n] = rect(t);
    const G = 64;
    const cell = (e - w) / G;
    const gi = (x, lo) => Math.min(G - 1, Math.max(0, Math.floor((x - lo) / cell)));
    const grid = Array.from({ length: G * G }, () => []);
    pts.forEach((p, i) => grid[gi(p[0], w) + G * gi(p[1], s)].push(i));
    for (let k = 0; k < tri.length; k += 3) {
      const [a, b, c] = [d.verts[tri[k]], d.verts[tri[k + 1]], d.verts[tri[k + 2]]];
      const det = (b.lon - a.lon) * (c.lat - a.lat) - (c.lon - a.lon) * (b.lat - a.lat);
      const gx0 = gi(Math.min(a.lon, b.lon, c.lon), w);
      const gx1 = gi(Math.max(a.lon, b.lon, c.lon), w);
      const gy0 = gi(Math.min(a.lat, b.lat, c.lat), s);
      const gy1 = gi(Math.max(a.lat, b.lat, c.lat), s);
      for (let gx = gx0; gx <= gx1; gx++) {
        for (let gy = gy0; gy <= gy1; gy++) {
          for (const i of grid[gx + G * gy]) {
            const [x, y, h] = pts[i];
            const l1 = ((b.lon - x) * (c.lat - y) - (c.lon - x) * (b.lat - y)) / det;
            const l2 = ((c.lon - x) * (a.lat - y) - (a.lon - x) * (c.lat - y)) / det;
            const l3 = 1 - l1 - l2;
            if (l1 < -1e-9 || l2 < -1e-9 || l3 < -1e-9) continue;
            const z = l1 * a.h + l2 * b.h + l3 * c.h;
            if (!(Math.abs(z - h) <= maxError + deviation + 1e-6)) {
              assert.fail(`${key(t)}: DEM ${h} at ${x},${y}, tile ${z}, bound ${maxError} + ${deviation}`);
            }
            done[i] = 1;
          }
        }
      }
    }
    assert.equal(done.reduce((a, v) => a + v, 0), pts.length, `${key(t)}: DEM samples outside every triangle`);
    checked += pts.length;
  }
  assert.ok(checked > 100000, `only ${checked} samples`);
});

test('same-zoom neighbours share their border vertices', () => {
  let borders = 0;
  for (const t of tiles(L)) {
    const a = decoded.get(key(t));
    for (const [dx, dy] of [[1, 0], [0, 1]]) {
      const b = decoded.get(key({ z: t.z, x: t.x + dx, y: t.y + dy }));
      if (!b) continue;
      // East: a's u = 32767 against b's u = 0, by v; north: v, by u.
      const side = (d, fixed, value) => new Map(d.verts.filter((p) => p[fixed] === value).map((p) => [fixed === 'u' ? p.v : p.u, p]));
      const fixed = dx ? 'u' : 'v';
      const ea = side(a, fixed, 32767);
      const eb = side(b, fixed, 0);
      assert.deepEqual([...ea.keys()].sort((x, y) => x - y), [...eb.keys()].sort((x, y) => x - y), `${key(t)} border positions`);
      for (const [k, p] of ea) {
        const q = eb.get(k);
        assert.ok(Math.abs(p.lon - q.lon) < 1e-9 && Math.abs(p.lat - q.lat) < 1e-9, `${key(t)} border position`);
        assert.ok(Math.abs(p.h - q.h) <= (a.step + b.step) / 2 + 1e-6, `${key(t)} border height ${p.h} vs ${q.h}`);
      }
      borders++;
    }
  }
  assert.ok(borders > 100, `only ${borders} borders`);
});
