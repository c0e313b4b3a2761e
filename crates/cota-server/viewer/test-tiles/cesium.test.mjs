// CesiumJS (the npm `cesium` package) in headless Debian Chromium against a
// local static server of a cota pyramid:
//  * sampleTerrainMostDetailed agrees with the DEM at DEM samples within the
//    finest zoom's bound e_Z;
//  * beyond the data's edge (a line of points crossing the footprint's east
//    edge outward) it is within e_Z of the ellipsoid (0 m) farther than two
//    finest-zoom tiles from the data (the profile is printed);
//  * rendered views: 60 km and 800 km over the data and a few km up (shaded
//    relief, no holes), 12,000 km and 800 km looking at the horizon (the
//    globe's outline against space: the fraction of black pixels within 2
//    percentage points of the same view over CesiumJS's
//    EllipsoidTerrainProvider), and a few km up looking across the data's edge.
// Screenshots: $COTA_TILES_SCREENSHOT (default target/tiles-cesium.png) and
// beside it the same name with -12000km, -12000km-ellipsoid, -800km,
// -800km-horizon, -800km-horizon-ellipsoid, -ground and -edge before .png.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { requireEnv, tilesDir, layer, bounds, dem, footprint, outside, tileDeg } from './common.mjs';

requireEnv();
const here = path.dirname(fileURLToPath(import.meta.url));
const cesiumDir = path.join(here, '..', 'node_modules', 'cesium', 'Build', 'Cesium');
const screenshot = process.env.COTA_TILES_SCREENSHOT || path.join(here, '..', '..', '..', '..', 'target', 'tiles-cesium.png');
const L = layer();
const maxZoom = L.maxzoom;
const bound = bounds(L).get(maxZoom).maxError;
const D = dem();
const FP = footprint(D);
/** The name of a screenshot beside the main one. */
const shot = (tag) => screenshot.replace(/(\.png)?$/, `-${tag}.png`);

const TYPES = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8',
  '.json': 'application/json',
  '.terrain': 'application/vnd.quantized-mesh',
  '.png': 'image/png',
  '.jpg': 'image/jpeg',
  '.svg': 'image/svg+xml',
  '.wasm': 'application/wasm',
};

const PAGE = `<!doctype html><html><head><meta charset="utf-8">
<link rel="stylesheet" href="/cesium/Widgets/widgets.css">
<style>html,body,#c{margin:0;width:100%;height:100%;overflow:hidden}</style>
<script>window.CESIUM_BASE_URL = '/cesium/';</script>
<script src="/cesium/Cesium.js"></script></head><body><div id="c"></div></body></html>`;

/** Serves the page, Cesium's build and the pyramid (gzipped tiles with Content-Encoding). */
function serve(root, base, res) {
  const file = path.normalize(path.join(root, base));
  if (!file.startsWith(root) || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
    res.writeHead(404).end();
    return;
  }
  const bytes = fs.readFileSync(file);
  const headers = { 'Content-Type': TYPES[path.extname(file)] || 'application/octet-stream' };
  if (bytes[0] === 0x1f && bytes[1] === 0x8b && file.endsWith('.terrain')) headers['Content-Encoding'] = 'gzip';
  res.writeHead(200, headers).end(bytes);
}

const server = http.createServer((req, res) => {
  const url = new URL(req.url, 'http://localhost');
  const p = decodeURIComponent(url.pathname);
  if (p === '/') res.writeHead(200, { 'Content-Type': TYPES['.html'] }).end(PAGE);
  else if (p.startsWith('/cesium/')) serve(cesiumDir, p.slice('/cesium/'.length), res);
  else if (p.startsWith('/tiles/')) serve(path.resolve(tilesDir), p.slice('/tiles/'.length), res);
  else res.writeHead(404).end();
});
await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
const origin = `http://127.0.0.1:${server.address().port}`;

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync',
    '--enable-unsafe-swiftshader'],
});
const page = await browser.newPage({ viewport: { width: 800, height: 600 } });
const errors = [];
page.on('pageerror', (e) => errors.push(String(e)));
await page.goto(origin + '/');
await page.waitForFunction(() => typeof window.Cesium !== 'undefined');
await page.evaluate(async () => {
  const C = window.Cesium;
  const terrainProvider = await C.CesiumTerrainProvider.fromUrl('/tiles/', {
    requestVertexNormals: true, requestWaterMask: true, requestMetadata: true,
  });
  const viewer = new C.Viewer('c', {
    terrainProvider, baseLayer: false, animation: false, timeline: false, baseLayerPicker: false,
    geocoder: false, homeButton: false, sceneModePicker: false, navigationHelpButton: false,
    fullscreenButton: false, infoBox: false, selectionIndicator: false, skyBox: false,
    skyAtmosphere: false, contextOptions: { webgl: { preserveDrawingBuffer: true } },
  });
  viewer.scene.globe.baseColor = C.Color.WHITE;
  window.viewer = viewer;
  window.terrainProvider = terrainProvider;

  /**
   * Points the camera (degrees, metres, degrees) with the globe shaded
   * (`lit`: a directional light along `light`, ECEF, or `lightEnu`, east,
   * north, up at the camera's longitude and latitude) or flat (base colour
   * only, no ground atmosphere or fog: the globe's outline against black
   * space), then renders until every tile is loaded on three frames running.
   */
  window.show = async ({ lon, lat, height, heading = 0, pitch = -90, lit = false, light = [1, 1, -0.3], lightEnu, intensity = 1 }) => {
    const v = window.viewer;
    const g = v.scene.globe;
    g.enableLighting = lit;
    g.showGroundAtmosphere = lit;
    v.scene.fog.enabled = lit;
    let direction = new C.Cartesian3(...light);
    if (lightEnu) {
      const enu = C.Transforms.eastNorthUpToFixedFrame(C.Cartesian3.fromDegrees(lon, lat));
      direction = C.Matrix4.multiplyByPointAsVector(enu, new C.Cartesian3(...lightEnu), new C.Cartesian3());
    }
    v.scene.light = new C.DirectionalLight({ direction: C.Cartesian3.normalize(direction, direction), intensity });
    v.camera.setView({
      destination: C.Cartesian3.fromDegrees(lon, lat, height),
      orientation: { heading: C.Math.toRadians(heading), pitch: C.Math.toRadians(pitch), roll: 0 },
    });
    const t0 = Date.now();
    let loaded = 0;
    while (Date.now() - t0 < 90000 && loaded < 3) {
      v.scene.render();
      loaded = g.tilesLoaded ? loaded + 1 : 0;
      await new Promise((r) => setTimeout(r, 50));
    }
    v.scene.render();
    return { loaded: loaded >= 3, ms: Date.now() - t0 };
  };

  /** The canvas's pixels: the fraction that are black (space) and the luminance spread. */
  window.pixels = () => {
    const src = window.viewer.scene.canvas;
    const cv = document.createElement('canvas');
    [cv.width, cv.height] = [src.width, src.height];
    const g = cv.getContext('2d');
    g.drawImage(src, 0, 0);
    const px = g.getImageData(0, 0, cv.width, cv.height).data;
    let black = 0;
    let blackBelow = 0;
    const lum = [];
    for (let i = 0; i < px.length; i += 4) {
      const dark = Math.max(px[i], px[i + 1], px[i + 2]) <= 24;
      black += dark;
      if (dark && i >= px.length / 2) blackBelow++;
      if (i % 28 === 0) lum.push(0.299 * px[i] + 0.587 * px[i + 1] + 0.114 * px[i + 2]);
    }
    const mean = lum.reduce((a, b) => a + b, 0) / lum.length;
    const sd = Math.sqrt(lum.reduce((a, b) => a + (b - mean) ** 2, 0) / lum.length);
    const levels = new Set(lum.map((l) => Math.round(l))).size;
    return { black: black / (px.length / 4), blackBelow: blackBelow / (px.length / 8), sd, levels };
  };
});
after(async () => {
  await browser.close();
  server.close();
});

/** Heights of CesiumJS's sampleTerrainMostDetailed at the points, and the zoom it sampled each at. */
async function sample(points) {
  return page.evaluate(async (pts) => {
    const C = window.Cesium;
    const carto = pts.map((q) => C.Cartographic.fromDegrees(q.lon, q.lat));
    const out = await C.sampleTerrainMostDetailed(window.terrainProvider, carto);
    // The zoom it sampled at: the most detailed available there, once its tiles' metadata loaded.
    const zoom = (c) => window.terrainProvider.availability.computeMaximumLevelAtPosition(c);
    return out.map((c) => ({ h: c.height, zoom: zoom(c) }));
  }, points);
}

/** Shows the view, checks that its tiles loaded, saves the screenshot; the pixels' figures. */
async function capture(view, file) {
  const r = await page.evaluate((v) => window.show(v), view);
  assert.ok(r.loaded, `tiles never finished loading for ${JSON.stringify(view)}`);
  const stats = await page.evaluate(() => window.pixels());
  fs.mkdirSync(path.dirname(file), { recursive: true });
  await page.screenshot({ path: file });
  console.log(`# ${JSON.stringify(view)}: black ${(100 * stats.black).toFixed(2)} %, luminance sd ${stats.sd.toFixed(1)}, ${stats.levels} levels, ${r.ms} ms; screenshot ${file}`);
  return stats;
}

/** The view over cota's terrain and over CesiumJS's ellipsoid: black fractions within 2 percentage points. */
async function againstEllipsoid(view, tag) {
  const cota = await capture(view, shot(tag));
  await page.evaluate(() => { window.viewer.scene.terrainProvider = new window.Cesium.EllipsoidTerrainProvider(); });
  let ellipsoid;
  try {
    ellipsoid = await capture(view, shot(`${tag}-ellipsoid`));
  } finally {
    await page.evaluate(() => { window.viewer.scene.terrainProvider = window.terrainProvider; });
  }
  const gap = 100 * Math.abs(cota.black - ellipsoid.black);
  console.log(`# ${tag}: black pixels ${(100 * cota.black).toFixed(2)} % over cota's tiles, ${(100 * ellipsoid.black).toFixed(2)} % over the ellipsoid (${gap.toFixed(2)} points apart)`);
  assert.ok(ellipsoid.black > 0.05 && ellipsoid.black < 0.95, `the ellipsoid view should show both globe and space: ${ellipsoid.black}`);
  assert.ok(gap <= 2, `${tag}: ${(100 * cota.black).toFixed(2)} % black over cota's tiles vs ${(100 * ellipsoid.black).toFixed(2)} % over the ellipsoid`);
  assert.deepEqual(errors, []);
}

test('sampleTerrainMostDetailed agrees with the DEM at DEM samples within e_Z', async () => {
  // DEM samples (exactly at their positions) on a 21 × 21 grid over each SRTM tile, its edges included.
  const pts = [];
  for (const p of D.parts) {
    for (let j = 0; j <= 20; j++) for (let i = 0; i <= 20; i++) {
      const [c, r] = [Math.round((i / 20) * (p.n - 1)), Math.round((j / 20) * (p.n - 1))];
      const h = p.h[r * p.n + c];
      if (h !== -32768) pts.push({ lon: p.lon + c / (p.n - 1), lat: p.lat + 1 - r / (p.n - 1), h });
    }
  }
  const got = await sample(pts);
  assert.equal(got.length, pts.length);
  let worst = 0;
  pts.forEach((q, k) => {
    const d = Math.abs(got[k].h - q.h);
    worst = Math.max(worst, d);
    assert.equal(got[k].zoom, maxZoom, `at ${q.lon},${q.lat}: sampled at zoom ${got[k].zoom}`);
    assert.ok(d <= bound + 1e-3, `at ${q.lon},${q.lat}: Cesium ${got[k].h}, DEM ${q.h}, e_${maxZoom} ${bound}`);
  });
  assert.ok(pts.length > 400, `only ${pts.length} points`);
  console.log(`# ${pts.length} DEM samples, largest |Cesium − DEM| ${worst.toFixed(3)} m, e_${maxZoom} ${bound.toFixed(3)} m`);
  assert.deepEqual(errors, []);
});

test("beyond the data's edge the terrain is the ellipsoid within e_Z", async () => {
  // The footprint's east edge, at the latitude of its highest DEM sample: the steepest fall.
  const p = D.parts.reduce((a, b) => (b.lon > a.lon ? b : a));
  const east = p.lon + 1;
  let row = 0;
  for (let r = 0; r < p.n; r++) if (p.h[r * p.n + p.n - 1] > p.h[row * p.n + p.n - 1]) row = r;
  const lat = p.lat + 1 - row / (p.n - 1);
  const pts = Array.from({ length: 50 }, (_, k) => ({ lon: east - 0.05 + (0.15 * k) / 49, lat }));
  const got = await sample(pts);
  const far = 2 * tileDeg(maxZoom);
  console.log(`# edge profile at latitude ${lat.toFixed(5)} (DEM ${p.h[row * p.n + p.n - 1]} m at the edge, ${east}°); far = ${far.toFixed(4)}° (2 tiles of zoom ${maxZoom})`);
  console.log('#   longitude   outside°  zoom  Cesium m   DEM m');
  let checked = 0;
  let worst = 0;
  const bad = [];
  pts.forEach((q, k) => {
    const out = outside(FP, q.lon, q.lat);
    const ref = D.at(q.lon, q.lat);
    console.log(`#   ${q.lon.toFixed(5)}  ${out.toFixed(5)}  ${String(got[k].zoom).padStart(4)}  ${got[k].h.toFixed(2).padStart(8)}  ${ref === undefined ? '-' : ref.toFixed(2)}`);
    if (out > far) {
      checked++;
      worst = Math.max(worst, Math.abs(got[k].h));
      if (!(Math.abs(got[k].h) <= bound)) bad.push(`${q.lon.toFixed(5)},${q.lat.toFixed(5)}: ${got[k].h.toFixed(2)} m (zoom ${got[k].zoom})`);
    }
  });
  console.log(`# ${checked} points farther than ${far.toFixed(4)}° out: largest |h| ${worst.toFixed(3)} m, e_${maxZoom} ${bound.toFixed(3)} m`);
  assert.ok(checked >= 3, `only ${checked} points far outside`);
  assert.deepEqual(bad, [], `heights beyond the data farther than e_${maxZoom} = ${bound.toFixed(3)} m from the ellipsoid`);
  // A few km up, outside the edge, looking back west across it (lit from the north-east, 35° up, dimmed).
  const h0 = D.at(east - 0.02, lat) ?? 0;
  const view = { lon: east + 0.06, lat, height: Math.max(1500, h0 + 1000), heading: 270, pitch: -12, lit: true, lightEnu: [-0.55, -0.6, -0.55], intensity: 0.6 };
  await capture(view, shot('edge'));
  assert.deepEqual(errors, []);
});

test('a rendered view shows terrain', async () => {
  const p = D.parts[0];
  const view = { lon: p.lon + 0.5, lat: p.lat - 0.45, height: 60000, pitch: -35, lit: true };
  const stats = await capture(view, screenshot);
  const h = await page.evaluate(({ lon, lat }) => window.viewer.scene.globe.getHeight(window.Cesium.Cartographic.fromDegrees(lon, lat)), { lon: p.lon + 0.5, lat: p.lat + 0.5 });
  const ref = D.at(p.lon + 0.5, p.lat + 0.5);
  assert.ok(h !== undefined && Math.abs(h - ref) < 300, `globe height ${h} vs DEM ${ref}`);
  assert.ok(stats.sd > 8 && stats.levels > 40, `the view looks flat: ${JSON.stringify(stats)}`);
  assert.deepEqual(errors, []);
});

test('near the ground over the data: shaded relief', async () => {
  // The highest DEM sample at least 0.15° inside the footprint, seen from 5 km south of it, 2 km above it.
  let best = { h: -Infinity };
  for (const p of D.parts) {
    for (let r = 0; r < p.n; r += 2) {
      for (let c = 0; c < p.n; c += 2) {
        const [lon, lat] = [p.lon + c / (p.n - 1), p.lat + 1 - r / (p.n - 1)];
        const inner = FP.some(([w, s, e, n]) => lon - w >= 0.15 && e - lon >= 0.15 && lat - s >= 0.15 && n - lat >= 0.15);
        if (inner && p.h[r * p.n + c] > best.h) best = { h: p.h[r * p.n + c], lon, lat };
      }
    }
  }
  const view = { lon: best.lon, lat: best.lat - 0.045, height: best.h + 2000, heading: 0, pitch: -15, lit: true };
  const stats = await capture(view, shot('ground'));
  assert.equal(stats.blackBelow, 0, 'black pixels (holes) in the lower half of the view');
  assert.ok(stats.sd > 8 && stats.levels > 40, `the view looks flat: ${JSON.stringify(stats)}`);
  assert.deepEqual(errors, []);
});

test('from 800 km over the data: its relief seen, tiles loaded', async () => {
  const p = D.parts[0];
  const stats = await capture({ lon: p.lon + 0.5, lat: p.lat + 0.5, height: 8e5, lit: true }, shot('800km'));
  assert.equal(stats.black, 0, 'black pixels looking down from 800 km');
  assert.ok(stats.sd > 2 && stats.levels > 20, `the view looks flat: ${JSON.stringify(stats)}`);
  assert.deepEqual(errors, []);
});

test("from 12,000 km the globe's outline matches the ellipsoid's (black pixels within 2 points)", async () => {
  const p = D.parts[0];
  await againstEllipsoid({ lon: p.lon + 0.5, lat: p.lat + 0.5, height: 12e6 }, '12000km');
});

test("from 800 km the horizon matches the ellipsoid's (black pixels within 2 points)", async () => {
  const p = D.parts[0];
  await againstEllipsoid({ lon: p.lon + 0.5, lat: p.lat - 2, height: 8e5, heading: 0, pitch: -20 }, '800km-horizon');
});
