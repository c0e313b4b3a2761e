// A tiny, valid quantized-mesh-1.0 tile set written by hand (the Cesium
// page's test until `cota tiles` output is at hand): layer.json and the two
// level-0 tiles of the geographic (EPSG:4326) TMS pyramid, each a small
// grid of vertices with a gentle relief; the east tile is gzipped.
// Format: https://github.com/CesiumGS/quantized-mesh (header, zig-zag delta
// u/v/height, high-water-mark indices, edge vertex lists).
import { mkdirSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { gzipSync } from 'node:zlib';

const A = 6378137.0, B = 6356752.314245;

function ecef(lonDeg, latDeg, h) {
  const lon = (lonDeg * Math.PI) / 180, lat = (latDeg * Math.PI) / 180;
  const e2 = 1 - (B * B) / (A * A);
  const n = A / Math.sqrt(1 - e2 * Math.sin(lat) ** 2);
  return [(n + h) * Math.cos(lat) * Math.cos(lon), (n + h) * Math.cos(lat) * Math.sin(lon), (n * (1 - e2) + h) * Math.sin(lat)];
}

const zig = (v) => ((v << 1) ^ (v >> 31)) >>> 0;

/** One tile of `k` × `k` vertices over [west, east] × [south, north] degrees. */
export function tile(west, south, east, north, k, heightAt) {
  const us = [], vs = [], hs = [], lonlat = [];
  let hmin = Infinity, hmax = -Infinity;
  for (let j = 0; j < k; j++) {
    for (let i = 0; i < k; i++) {
      const lon = west + ((east - west) * i) / (k - 1), lat = south + ((north - south) * j) / (k - 1);
      const h = heightAt(lon, lat);
      lonlat.push([lon, lat, h]);
      hmin = Math.min(hmin, h);
      hmax = Math.max(hmax, h);
      us.push(Math.round((32767 * i) / (k - 1)));
      vs.push(Math.round((32767 * j) / (k - 1)));
    }
  }
  for (const [, , h] of lonlat) hs.push(Math.round((32767 * (h - hmin)) / Math.max(hmax - hmin, 1)));
  const tris = [];
  for (let j = 0; j + 1 < k; j++) {
    for (let i = 0; i + 1 < k; i++) {
      const a = j * k + i, b = a + 1, c = a + k, d = c + 1;
      tris.push(a, b, d, a, d, c);
    }
  }
  const n = k * k;
  const edges = {
    west: [...Array(k).keys()].map((j) => j * k),
    south: [...Array(k).keys()],
    east: [...Array(k).keys()].map((j) => j * k + k - 1),
    north: [...Array(k).keys()].map((i) => (k - 1) * k + i),
  };
  const size = 88 + 4 + 6 * n + 4 + 2 * tris.length + 4 * 4 + 2 * 4 * k;
  const buf = new ArrayBuffer(size);
  const dv = new DataView(buf);
  let o = 0;
  const f64 = (v) => { dv.setFloat64(o, v, true); o += 8; };
  const f32 = (v) => { dv.setFloat32(o, v, true); o += 4; };
  const u32 = (v) => { dv.setUint32(o, v, true); o += 4; };
  const u16 = (v) => { dv.setUint16(o, v, true); o += 2; };
  const c = ecef((west + east) / 2, (south + north) / 2, (hmin + hmax) / 2);
  c.forEach(f64);
  f32(hmin);
  f32(hmax);
  c.forEach(f64);
  let r = 0;
  for (const [lon, lat, h] of lonlat) {
    const p = ecef(lon, lat, h);
    r = Math.max(r, Math.hypot(p[0] - c[0], p[1] - c[1], p[2] - c[2]));
  }
  f64(r);
  const top = ecef((west + east) / 2, (south + north) / 2, hmax + r);
  [top[0] / A, top[1] / A, top[2] / B].forEach(f64);
  u32(n);
  for (const arr of [us, vs, hs]) {
    let prev = 0;
    for (const v of arr) {
      u16(zig(v - prev));
      prev = v;
    }
  }
  u32(tris.length / 3);
  let highest = 0;
  for (const t of tris) {
    u16(highest - t);
    if (t === highest) highest++;
  }
  for (const side of ['west', 'south', 'east', 'north']) {
    u32(edges[side].length);
    edges[side].forEach(u16);
  }
  return new Uint8Array(buf, 0, o);
}

/** Writes layer.json and 0/0/0.terrain, 0/1/0.terrain (gzipped) under `dir`. */
export function writeTileSet(dir) {
  const relief = (lon, lat) => 200 + 150 * Math.sin(lon / 7) * Math.cos(lat / 5);
  mkdirSync(join(dir, '0/0'), { recursive: true });
  mkdirSync(join(dir, '0/1'), { recursive: true });
  writeFileSync(join(dir, '0/0/0.terrain'), tile(-180, -90, 0, 90, 17, relief));
  writeFileSync(join(dir, '0/1/0.terrain'), gzipSync(tile(0, -90, 180, 90, 17, relief)));
  const layer = {
    tilejson: '2.1.0',
    name: 'cota test tiles',
    version: '1.0.0',
    format: 'quantized-mesh-1.0',
    scheme: 'tms',
    projection: 'EPSG:4326',
    tiles: ['{z}/{x}/{y}.terrain?v={version}'],
    bounds: [-180, -90, 180, 90],
    minzoom: 0,
    maxzoom: 0,
    available: [[{ startX: 0, startY: 0, endX: 1, endY: 0 }]],
  };
  writeFileSync(join(dir, 'layer.json'), JSON.stringify(layer, null, 2));
}
