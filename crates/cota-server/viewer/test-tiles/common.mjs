// Shared by the tiles tests (test-tiles/) and the browser test of the
// CesiumJS page (test-browser/): the pyramid and the DEM it was made from.
//
// Environment:
//   COTA_TILES         the pyramid directory (layer.json, {z}/{x}/{y}.terrain)
//   COTA_TILES_DEM     the SRTM files it was made from, comma-separated
//                      (.hgt or single-member .hgt.zip; position from the name)
//   COTA_TILES_REPORT  `cota tiles --json` output (its per-zoom figures are
//                      printed beside the tests' own; no bound uses it)
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';

export const tilesDir = process.env.COTA_TILES;
export const demFiles = (process.env.COTA_TILES_DEM || '').split(',').filter(Boolean);
export const reportPath = process.env.COTA_TILES_REPORT;

export function requireEnv() {
  if (!tilesDir || demFiles.length === 0 || !reportPath) {
    throw new Error('set COTA_TILES, COTA_TILES_DEM and COTA_TILES_REPORT (see .ci/run)');
  }
}

export const layer = () => JSON.parse(fs.readFileSync(path.join(tilesDir, 'layer.json'), 'utf8'));
export const report = () => JSON.parse(fs.readFileSync(reportPath, 'utf8'));

/** The bound e_z of each zoom and its quantization margin, from layer.json. */
export function bounds(l) {
  const out = new Map();
  for (const e of l.cota.errors) out.set(e.zoom, { maxError: e.max_error_m, margin: e.max_error_m - e.threshold_m });
  return out;
}

/** Every tile of layer.json's `available`. */
export function* tiles(l) {
  for (let z = 0; z < l.available.length; z++) {
    for (const r of l.available[z]) {
      for (let y = r.startY; y <= r.endY; y++) for (let x = r.startX; x <= r.endX; x++) yield { z, x, y };
    }
  }
}

/** The tile's bytes, inflated when gzipped, as an ArrayBuffer. */
export function tileBuffer(t) {
  let b = fs.readFileSync(path.join(tilesDir, `${t.z}`, `${t.x}`, `${t.y}.terrain`));
  if (b[0] === 0x1f && b[1] === 0x8b) b = zlib.gunzipSync(b);
  return b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength);
}

/** [west, south, east, north] of a geographic TMS tile, degrees. */
export function rect(t) {
  const size = 180 / 2 ** t.z;
  const w = -180 + t.x * size;
  const s = -90 + t.y * size;
  return [w, s, w + size, s + size];
}

/** The bytes of the one member of a ZIP archive (deflated or stored). */
function unzipOne(buf) {
  if (buf.readUInt32LE(0) !== 0x04034b50) throw new Error('not a ZIP archive');
  const method = buf.readUInt16LE(8);
  let size = buf.readUInt32LE(18);
  const nameLen = buf.readUInt16LE(26);
  const extraLen = buf.readUInt16LE(28);
  const start = 30 + nameLen + extraLen;
  if (size === 0) {
    // Sizes in the central directory (data descriptor): find it from the end.
    const eocd = buf.lastIndexOf(Buffer.from([0x50, 0x4b, 0x05, 0x06]));
    const cd = buf.readUInt32LE(eocd + 16);
    size = buf.readUInt32LE(cd + 20);
  }
  const data = buf.subarray(start, start + size);
  return method === 8 ? zlib.inflateRawSync(data) : data;
}

/** An SRTM tile: south-west corner from the name, n×n big-endian int16. */
function readSrtm(file) {
  const m = /([NS])(\d{2})([EW])(\d{3})/i.exec(path.basename(file));
  if (!m) throw new Error(`${file}: expected an SRTM name like N00E010.hgt`);
  const lat = (m[1].toUpperCase() === 'N' ? 1 : -1) * Number(m[2]);
  const lon = (m[3].toUpperCase() === 'E' ? 1 : -1) * Number(m[4]);
  let buf = fs.readFileSync(file);
  if (file.endsWith('.zip')) buf = unzipOne(buf);
  const n = Math.round(Math.sqrt(buf.length / 2));
  const h = new Float64Array(n * n);
  for (let i = 0; i < n * n; i++) h[i] = buf.readInt16BE(2 * i);
  return { lat, lon, n, h };
}

/** The DEM of `files`: SRTM tiles, bilinear heights and the list of their samples. */
export function readDem(files) {
  const parts = files.map(readSrtm);
  const find = (lon, lat) => parts.find((p) => lon >= p.lon && lon <= p.lon + 1 && lat >= p.lat && lat <= p.lat + 1);
  return {
    parts,
    /** Bilinear height at (lon, lat), or undefined outside every tile. */
    at(lon, lat) {
      const p = find(lon, lat);
      if (!p) return undefined;
      const k = p.n - 1;
      const x = (lon - p.lon) * k;
      const y = (p.lat + 1 - lat) * k;
      const i = Math.min(Math.floor(x), k - 1);
      const j = Math.min(Math.floor(y), k - 1);
      const fx = x - i;
      const fy = y - j;
      const z = (c, r) => p.h[r * p.n + c];
      // SRTM voids (-32768) were filled by cota: no reference there.
      if ([z(i, j), z(i + 1, j), z(i, j + 1), z(i + 1, j + 1)].some((v) => v === -32768)) return undefined;
      const top = z(i, j) + (z(i + 1, j) - z(i, j)) * fx;
      const bottom = z(i, j + 1) + (z(i + 1, j + 1) - z(i, j + 1)) * fx;
      return top + (bottom - top) * fy;
    },
  };
}

/** The DEM of COTA_TILES_DEM. */
export const dem = () => readDem(demFiles);

// ---- WGS 84, written here from the ellipsoid's definition (no code of cota's).

/** WGS 84 semi-major and semi-minor axes, metres. */
export const WGS84_A = 6378137.0;
export const WGS84_B = 6356752.314245179;
const E2 = 1 - (WGS84_B * WGS84_B) / (WGS84_A * WGS84_A);
const RAD = Math.PI / 180;

/** Earth-centred (ECEF) metres of a geodetic position: degrees, metres along the normal. */
export function toEcef(lon, lat, h) {
  const l = lon * RAD;
  const p = lat * RAD;
  const sp = Math.sin(p);
  const cp = Math.cos(p);
  const n = WGS84_A / Math.sqrt(1 - E2 * sp * sp); // prime vertical radius
  return [(n + h) * cp * Math.cos(l), (n + h) * cp * Math.sin(l), (n * (1 - E2) + h) * sp];
}

/** The ellipsoid's outward unit normal at a geodetic longitude, latitude (degrees). */
export function normalAt(lon, lat) {
  const l = lon * RAD;
  const p = lat * RAD;
  return [Math.cos(p) * Math.cos(l), Math.cos(p) * Math.sin(l), Math.sin(p)];
}

/**
 * Geodetic longitude, latitude (degrees) and height (metres along the
 * normal) of an ECEF position: the latitude by fixed-point iteration of
 * tan φ = z / (r (1 − e² N/(N + h))) until it moves less than 1e-14 rad
 * (a few steps near the surface), then h from whichever of r and z is
 * better conditioned at that latitude.
 */
export function toGeodetic(x, y, z) {
  const r = Math.hypot(x, y);
  const lon = Math.atan2(y, x);
  let lat = Math.atan2(z, r * (1 - E2));
  let h = 0;
  for (let k = 0; k < 20; k++) {
    const s = Math.sin(lat);
    const c = Math.cos(lat);
    const n = WGS84_A / Math.sqrt(1 - E2 * s * s);
    h = Math.abs(c) > 0.5 ? r / c - n : z / s - n * (1 - E2);
    const next = Math.atan2(z, r * (1 - (E2 * n) / (n + h)));
    const done = Math.abs(next - lat) < 1e-14;
    lat = next;
    if (done) break;
  }
  const s = Math.sin(lat);
  const c = Math.cos(lat);
  const n = WGS84_A / Math.sqrt(1 - E2 * s * s);
  h = Math.abs(c) > 0.5 ? r / c - n : z / s - n * (1 - E2);
  return { lon: lon / RAD, lat: lat / RAD, h };
}

// ---- The DEM's footprint and the tiling.

/** The footprint of the DEM: one [west, south, east, north] per SRTM tile (its samples' extent). */
export const footprint = (d) => d.parts.map((p) => [p.lon, p.lat, p.lon + 1, p.lat + 1]);

/**
 * How far (degrees, the larger of the longitude and latitude gaps) a point
 * is outside the footprint; 0 inside or on its edge. Longitudes wrap.
 */
export function outside(rects, lon, lat) {
  let best = Infinity;
  for (const [w, s, e, n] of rects) {
    let dx = Infinity;
    for (const k of [-360, 0, 360]) {
      const x = lon + k;
      dx = Math.min(dx, Math.max(w - x, 0, x - e));
    }
    const dy = Math.max(s - lat, 0, lat - n);
    best = Math.min(best, Math.max(dx, dy));
  }
  return best;
}

/** The area (square degrees) a rectangle shares with the footprint (its rectangles do not overlap but may share edges). */
export function sharedArea(rects, [w, s, e, n]) {
  let a = 0;
  for (const [fw, fs, fe, fn] of rects) {
    a += Math.max(0, Math.min(e, fe) - Math.max(w, fw)) * Math.max(0, Math.min(n, fn) - Math.max(s, fs));
  }
  return a;
}

/** The width (degrees) of a tile of zoom z in the geographic TMS tiling (two root tiles). */
export const tileDeg = (z) => 180 / 2 ** z;

/** A seeded pseudo-random generator in [0, 1) (mulberry32): the same points every run. */
export function random(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}
