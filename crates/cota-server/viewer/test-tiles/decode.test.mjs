// Every tile of a cota pyramid, decoded by two real clients' decoders:
// @loaders.gl/terrain's QuantizedMeshLoader and @here/quantized-mesh-decoder.
// Checks that they agree, that same-zoom neighbours share their border
// vertices, and that every tile is within its zoom's bound e_z of the DEM
// as the client draws it: flat triangles between the vertices' ECEF
// positions on WGS 84, heights along the ellipsoid normal.
//  * At every DEM sample of every tile (the source's own samples, not a
//    resampled lattice): the normal through the sample's foot on the
//    ellipsoid meets the drawn surface within e_z of the sample's height;
//    the height interpolated linearly in longitude and latitude (what
//    CesiumJS's sampleTerrain returns) is within e_z too.
//  * At random points of every drawn triangle (and its vertices): taken back
//    to geodetic coordinates, within e_z of the ellipsoid (0 m) farther than
//    two finest-zoom tiles from the DEM's footprint; inside the footprint the
//    deviation from the DEM's bilinear surface is between samples, so only
//    printed and held to a loose 3 e_z.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { parse } from '@loaders.gl/core';
import { QuantizedMeshLoader } from '@loaders.gl/terrain';
import hereModule from '@here/quantized-mesh-decoder';
import {
  requireEnv, layer, report, bounds, tiles, tileBuffer, rect, dem,
  toEcef, toGeodetic, footprint, outside, tileDeg, random, WGS84_A, WGS84_B,
} from './common.mjs';

// The package is a UMD bundle: its decoder is the CommonJS `default` export.
const hereDecode = hereModule.default ?? hereModule;

requireEnv();
const L = layer();
const B = bounds(L);
const R = report();
const D = dem();
const FP = footprint(D);
const maxZoom = L.maxzoom;
/** Farther than this (degrees) from the footprint, the drawn surface must be the ellipsoid. */
const far = 2 * tileDeg(maxZoom);
const fmt = (x) => (Number.isFinite(x) ? x.toFixed(3) : '-');

/** Decoded with both decoders; heights in metres, positions in degrees and ECEF metres. */
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
  const ecef = new Float64Array(3 * n);
  verts.forEach((p, i) => ecef.set(toEcef(p.lon, p.lat, p.h), 3 * i));
  return { here, lg, verts, ecef, step: (maxHeight - minHeight) / 32767 };
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

// ---- The drawn surface: flat ECEF triangles.

/** The tile's triangles as drawn: for each, its first vertex, two edges, normal and |normal|². */
function drawnTriangles(d) {
  const tri = d.here.triangleIndices;
  const P = d.ecef;
  const out = [];
  for (let k = 0; k < tri.length; k += 3) {
    const [a, b, c] = [3 * tri[k], 3 * tri[k + 1], 3 * tri[k + 2]];
    const p0 = [P[a], P[a + 1], P[a + 2]];
    const e1 = [P[b] - p0[0], P[b + 1] - p0[1], P[b + 2] - p0[2]];
    const e2 = [P[c] - p0[0], P[c + 1] - p0[1], P[c + 2] - p0[2]];
    const nrm = cross(e1, e2);
    out.push({ k: k / 3, p0, e1, e2, nrm, nn: dot(nrm, nrm) });
  }
  return out;
}

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];

/**
 * Where the line o + t·n (n the unit normal, o on the ellipsoid) meets the
 * triangle's plane: t (the drawn height along the normal) and the smallest
 * barycentric coordinate of the meeting point (≥ 0 when inside).
 */
function meet(T, o, n) {
  const [N0, N1, N2] = T.nrm;
  const den = N0 * n[0] + N1 * n[1] + N2 * n[2];
  if (!(Math.abs(den) > 1e-12 * Math.sqrt(T.nn))) return { t: NaN, inside: -Infinity };
  const [w0, w1, w2] = [o[0] - T.p0[0], o[1] - T.p0[1], o[2] - T.p0[2]];
  const t = -(N0 * w0 + N1 * w1 + N2 * w2) / den;
  // The meeting point relative to the first vertex, x = b1·e1 + b2·e2 in the plane:
  // b1 = (x × e2)·N / |N|², b2 = (e1 × x)·N / |N|².
  const [x0, x1, x2] = [w0 + t * n[0], w1 + t * n[1], w2 + t * n[2]];
  const [e0, e1, e2] = T.e2;
  const [f0, f1, f2] = T.e1;
  const b1 = ((x1 * e2 - x2 * e1) * N0 + (x2 * e0 - x0 * e2) * N1 + (x0 * e1 - x1 * e0) * N2) / T.nn;
  const b2 = ((f1 * x2 - f2 * x1) * N0 + (f2 * x0 - f0 * x2) * N1 + (f0 * x1 - f1 * x0) * N2) / T.nn;
  return { t, inside: Math.min(b1, b2, 1 - b1 - b2) };
}

/** The drawn height over (o, n) among `tris`: the triangle the line meets most inside. */
function bestMeet(tris, o, n) {
  let best = { t: NaN, inside: -Infinity };
  for (const T of tris) {
    const m = meet(T, o, n);
    if (m.inside > best.inside) best = m;
  }
  return best;
}

/** Triangles bucketed by their longitude/latitude boxes over the tile, to find the one over a point. */
function locator(t, d) {
  const [w, s, e, n] = rect(t);
  const tri = d.here.triangleIndices;
  const G = Math.max(4, Math.min(64, Math.ceil(Math.sqrt(tri.length / 3 / 2))));
  const gi = (x, lo, hi) => Math.min(G - 1, Math.max(0, Math.floor(((x - lo) / (hi - lo)) * G)));
  const cells = Array.from({ length: G * G }, () => []);
  for (let k = 0; k < tri.length; k += 3) {
    const [a, b, c] = [d.verts[tri[k]], d.verts[tri[k + 1]], d.verts[tri[k + 2]]];
    const [x0, x1] = [gi(Math.min(a.lon, b.lon, c.lon), w, e), gi(Math.max(a.lon, b.lon, c.lon), w, e)];
    const [y0, y1] = [gi(Math.min(a.lat, b.lat, c.lat), s, n), gi(Math.max(a.lat, b.lat, c.lat), s, n)];
    for (let y = y0; y <= y1; y++) for (let x = x0; x <= x1; x++) cells[x + G * y].push(k / 3);
  }
  /** The triangle whose longitude/latitude footprint holds the point, with the point's barycentric weights. */
  return (lon, lat) => {
    for (const k of cells[gi(lon, w, e) + G * gi(lat, s, n)]) {
      const a = d.verts[tri[3 * k]];
      const b = d.verts[tri[3 * k + 1]];
      const c = d.verts[tri[3 * k + 2]];
      const det = (b.lon - a.lon) * (c.lat - a.lat) - (c.lon - a.lon) * (b.lat - a.lat);
      const l1 = ((b.lon - lon) * (c.lat - lat) - (c.lon - lon) * (b.lat - lat)) / det;
      const l2 = ((c.lon - lon) * (a.lat - lat) - (a.lon - lon) * (c.lat - lat)) / det;
      const l3 = 1 - l1 - l2;
      if (l1 >= -1e-9 && l2 >= -1e-9 && l3 >= -1e-9) return { k, h: l1 * a.h + l2 * b.h + l3 * c.h };
    }
    return undefined;
  };
}

/**
 * Calls f(lon, lat, height, foot, normal) for every DEM sample inside the
 * tile's rectangle (voids skipped): `foot` the sample's position on the
 * ellipsoid (ECEF), `normal` the unit normal there (both reused: read them
 * before returning).
 */
function demSamples(t, f) {
  const [w, s, e, n] = rect(t);
  const e2 = 1 - (WGS84_B * WGS84_B) / (WGS84_A * WGS84_A);
  const foot = new Float64Array(3);
  const nrm = new Float64Array(3);
  for (const p of D.parts) {
    const k = p.n - 1;
    const c0 = Math.max(0, Math.ceil((w - p.lon) * k));
    const c1 = Math.min(k, Math.floor((e - p.lon) * k));
    const r0 = Math.max(0, Math.ceil((p.lat + 1 - n) * k));
    const r1 = Math.min(k, Math.floor((p.lat + 1 - s) * k));
    if (c0 > c1 || r0 > r1) continue;
    // Trigonometry per column and per row: the foot on the ellipsoid and the normal.
    const cl = [];
    for (let c = c0; c <= c1; c++) {
      const l = ((p.lon + c / k) * Math.PI) / 180;
      cl.push([Math.cos(l), Math.sin(l)]);
    }
    for (let r = r0; r <= r1; r++) {
      const lat = p.lat + 1 - r / k;
      const ph = (lat * Math.PI) / 180;
      const [sp, cp] = [Math.sin(ph), Math.cos(ph)];
      const N = WGS84_A / Math.sqrt(1 - e2 * sp * sp);
      for (let c = c0; c <= c1; c++) {
        const h = p.h[r * p.n + c];
        if (h === -32768) continue;
        const [clo, slo] = cl[c - c0];
        [nrm[0], nrm[1], nrm[2]] = [cp * clo, cp * slo, sp];
        [foot[0], foot[1], foot[2]] = [N * nrm[0], N * nrm[1], N * (1 - e2) * sp];
        f(p.lon + c / k, lat, h, foot, nrm);
      }
    }
  }
}

/** The same-zoom tiles around t that were written (decoded). */
function neighbours(t) {
  const out = [];
  for (let dy = -1; dy <= 1; dy++) {
    for (let dx = -1; dx <= 1; dx++) {
      const d = (dx || dy) && decoded.get(key({ z: t.z, x: t.x + dx, y: t.y + dy }));
      if (d) out.push(d);
    }
  }
  return out;
}

test('every DEM sample is within its zoom bound e_z as drawn (along the normal) and as sampled (linear in lon/lat)', () => {
  const perZoom = new Map();
  let checked = 0;
  let fallback = 0;
  for (const t of tiles(L)) {
    const d = decoded.get(key(t));
    const { maxError } = B.get(t.z);
    const tris = (d.tris ??= drawnTriangles(d));
    const find = locator(t, d);
    const zs = perZoom.get(t.z) ?? { drawn: 0, linear: 0, samples: 0, worstAt: '' };
    perZoom.set(t.z, zs);
    // Triangles sharing a vertex: the first fallback when the normal leaves the triangle below the sample.
    const around = Array.from({ length: d.verts.length }, () => []);
    const tri = d.here.triangleIndices;
    for (let k = 0; k < tri.length; k++) around[tri[k]].push(Math.floor(k / 3));
    demSamples(t, (lon, lat, h, o, n) => {
      const under = find(lon, lat);
      if (!under) assert.fail(`${key(t)}: DEM sample ${lon},${lat} under no triangle`);
      // As drawn: the normal line against the flat triangle over the sample, else its neighbours,
      // else every triangle of the tile and of its same-zoom neighbours.
      let m = meet(tris[under.k], o, n);
      if (m.inside < -1e-9) {
        fallback++;
        const near = new Set();
        for (const i of [3 * under.k, 3 * under.k + 1, 3 * under.k + 2]) for (const k of around[tri[i]]) near.add(tris[k]);
        m = bestMeet(near, o, n);
        if (m.inside < -1e-9) m = bestMeet(tris, o, n);
        for (const nb of m.inside < -1e-9 ? neighbours(t) : []) {
          const c = bestMeet((nb.tris ??= drawnTriangles(nb)), o, n);
          if (c.inside > m.inside) m = c;
        }
      }
      if (!(m.inside >= -1e-9)) assert.fail(`${key(t)}: no drawn triangle over the DEM sample ${lon},${lat} (best ${m.inside})`);
      const drawn = Math.abs(m.t - h);
      if (!(drawn <= maxError + 1e-6)) {
        assert.fail(`${key(t)}: DEM ${h} at ${lon},${lat}: drawn ${m.t} m along the normal, |Δ| ${drawn} > e_${t.z} ${maxError}`);
      }
      // Linear in longitude and latitude (the tile's parameter space).
      const lin = Math.abs(under.h - h);
      if (!(lin <= maxError + 1e-6)) {
        assert.fail(`${key(t)}: DEM ${h} at ${lon},${lat}: linear ${under.h}, |Δ| ${lin} > e_${t.z} ${maxError}`);
      }
      zs.linear = Math.max(zs.linear, lin);
      if (drawn > zs.drawn) [zs.drawn, zs.worstAt] = [drawn, `${key(t)} ${lon.toFixed(5)},${lat.toFixed(5)}`];
      zs.samples++;
      checked++;
    });
  }
  console.log('# at DEM samples: zoom, e_z, largest |drawn − DEM| (cota reports), largest |linear − DEM|, samples, where');
  for (const [z, s] of perZoom) {
    const rep = R.zooms.find((q) => q.zoom === z);
    console.log(`#   ${z} e=${fmt(B.get(z).maxError)} drawn=${fmt(s.drawn)} (${fmt(rep?.drawn_error_m)}) linear=${fmt(s.linear)} n=${s.samples} at ${s.worstAt}`);
  }
  console.log(`# ${checked} sample checks, ${fallback} met a neighbour of the triangle under them`);
  assert.ok(checked > 100000, `only ${checked} samples`);
});

test('random points of every drawn triangle: the ellipsoid within e_z away from the data, the DEM between samples', () => {
  // 4 to 8 points a triangle, at most about 2.5 million in all (the run's time).
  let triangles = 0;
  for (const d of decoded.values()) triangles += d.here.triangleIndices.length / 3;
  const PER_TRIANGLE = Math.max(4, Math.min(8, Math.floor(2.5e6 / triangles)));
  const perZoom = new Map();
  let points = 0;
  for (const t of tiles(L)) {
    const d = decoded.get(key(t));
    const { maxError } = B.get(t.z);
    const zs = perZoom.get(t.z) ?? { inside: 0, insideN: 0, insideAt: '', away: 0, awayN: 0, awayAt: '', between: 0 };
    perZoom.set(t.z, zs);
    const rnd = random(1 + t.z * 1000003 + t.x * 7919 + t.y * 104729);
    const P = d.ecef;
    const tri = d.here.triangleIndices;
    const visit = (x, y, z) => {
      const g = toGeodetic(x, y, z);
      const out = outside(FP, g.lon, g.lat);
      const where = () => `${key(t)} ${g.lon.toFixed(5)},${g.lat.toFixed(5)} h ${g.h.toFixed(2)}`;
      if (out > far) {
        const dev = Math.abs(g.h);
        if (!(dev <= maxError + 1e-6)) assert.fail(`${where()}: ${fmt(out)}° from the data, ${dev} m off the ellipsoid > e_${t.z} ${maxError}`);
        if (dev >= zs.away) [zs.away, zs.awayAt] = [dev, where()];
        zs.awayN++;
      } else if (out === 0) {
        const ref = D.at(g.lon, g.lat);
        if (ref === undefined) return;
        const dev = Math.abs(g.h - ref);
        if (!(dev <= 3 * maxError)) assert.fail(`${where()}: DEM ${ref}, |Δ| ${dev} > 3 e_${t.z} (sanity)`);
        if (dev >= zs.inside) [zs.inside, zs.insideAt] = [dev, `${where()} DEM ${ref.toFixed(2)}`];
        zs.insideN++;
      } else {
        zs.between++;
      }
      points++;
    };
    for (let i = 0; i < d.verts.length; i++) visit(P[3 * i], P[3 * i + 1], P[3 * i + 2]);
    for (let k = 0; k < tri.length; k += 3) {
      const [a, b, c] = [3 * tri[k], 3 * tri[k + 1], 3 * tri[k + 2]];
      for (let j = 0; j < PER_TRIANGLE; j++) {
        let [r1, r2] = [rnd(), rnd()];
        if (r1 + r2 > 1) [r1, r2] = [1 - r1, 1 - r2];
        const r0 = 1 - r1 - r2;
        visit(r0 * P[a] + r1 * P[b] + r2 * P[c], r0 * P[a + 1] + r1 * P[b + 1] + r2 * P[c + 1], r0 * P[a + 2] + r1 * P[b + 2] + r2 * P[c + 2]);
      }
    }
  }
  console.log(`# random drawn points (${PER_TRIANGLE} a triangle, and the vertices): zoom, e_z, largest |h| farther than ${fmt(far)}° from the data (count), largest |h − DEM bilinear| inside (count; between samples: not bounded), near the edge (unchecked)`);
  for (const [z, s] of perZoom) {
    const rep = R.zooms.find((q) => q.zoom === z);
    console.log(`#   ${z} e=${fmt(B.get(z).maxError)} away=${fmt(s.away)} (${s.awayN}) inside=${fmt(s.inside)} (${s.insideN}; cota's between_m ${fmt(rep?.between_m)}) near=${s.between}`);
    if (s.awayN) console.log(`#     away worst: ${s.awayAt}`);
    if (s.insideN) console.log(`#     inside worst: ${s.insideAt}`);
  }
  assert.ok(points > 100000, `only ${points} points`);
  assert.ok([...perZoom.values()].some((s) => s.awayN > 0), 'no point away from the data was checked');
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
