// CesiumJS (the npm `cesium` package) in headless Debian Chromium against a
// local static server of a cota pyramid: sampleTerrainMostDetailed must
// agree with the DEM within the finest zoom's bound (plus the lattice's own
// deviation), and a rendered view must show terrain. The screenshot is kept
// as target/tiles-cesium.png (or $COTA_TILES_SCREENSHOT).
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { requireEnv, tilesDir, layer, report, bounds, dem } from './common.mjs';

requireEnv();
const here = path.dirname(fileURLToPath(import.meta.url));
const cesiumDir = path.join(here, '..', 'node_modules', 'cesium', 'Build', 'Cesium');
const screenshot = process.env.COTA_TILES_SCREENSHOT || path.join(here, '..', '..', '..', '..', 'target', 'tiles-cesium.png');
const L = layer();
const maxZoom = L.maxzoom;
const bound = bounds(L).get(maxZoom).maxError + report().lattice.deviation_max_m;
const D = dem();

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
  viewer.scene.globe.enableLighting = true;
  viewer.scene.light = new C.DirectionalLight({ direction: new C.Cartesian3(1, 1, -0.3) });
  window.viewer = viewer;
  window.terrainProvider = terrainProvider;
});
after(async () => {
  await browser.close();
  server.close();
});

test('sampleTerrainMostDetailed agrees with the DEM', async () => {
  // DEM samples on a grid over the first SRTM tile, away from its edges.
  const p = D.parts[0];
  const pts = [];
  for (let j = 1; j < 20; j++) for (let i = 1; i < 20; i++) {
    const [c, r] = [Math.round((i / 20) * (p.n - 1)), Math.round((j / 20) * (p.n - 1))];
    const h = p.h[r * p.n + c];
    if (h !== -32768) pts.push({ lon: p.lon + c / (p.n - 1), lat: p.lat + 1 - r / (p.n - 1), h });
  }
  const got = await page.evaluate(async (points) => {
    const C = window.Cesium;
    const carto = points.map((q) => C.Cartographic.fromDegrees(q.lon, q.lat));
    const out = await C.sampleTerrainMostDetailed(window.terrainProvider, carto);
    return out.map((c) => c.height);
  }, pts);
  assert.equal(got.length, pts.length);
  let worst = 0;
  pts.forEach((q, k) => {
    const d = Math.abs(got[k] - q.h);
    worst = Math.max(worst, d);
    assert.ok(d <= bound + 1e-3, `at ${q.lon},${q.lat}: Cesium ${got[k]}, DEM ${q.h}, bound ${bound}`);
  });
  assert.ok(pts.length > 300, `only ${pts.length} points`);
  console.log(`# ${pts.length} points, largest |Cesium − DEM| ${worst.toFixed(3)} m, bound ${bound.toFixed(3)} m`);
  assert.deepEqual(errors, []);
});

test('a rendered view shows terrain', async () => {
  const p = D.parts[0];
  const stats = await page.evaluate(async ({ lon, lat }) => {
    const C = window.Cesium;
    const v = window.viewer;
    v.camera.setView({
      destination: C.Cartesian3.fromDegrees(lon + 0.5, lat - 0.45, 60000),
      orientation: { heading: 0, pitch: C.Math.toRadians(-35), roll: 0 },
    });
    const t0 = Date.now();
    while (Date.now() - t0 < 90000) {
      v.scene.render();
      if (v.scene.globe.tilesLoaded) break;
      await new Promise((r) => setTimeout(r, 100));
    }
    v.scene.render();
    const h = v.scene.globe.getHeight(C.Cartographic.fromDegrees(lon + 0.5, lat + 0.5));
    // Luminance spread over the globe's pixels: shaded relief, not a flat disc.
    const src = v.scene.canvas;
    const cv = document.createElement('canvas');
    [cv.width, cv.height] = [src.width, src.height];
    const g = cv.getContext('2d');
    g.drawImage(src, 0, 0);
    const px = g.getImageData(0, 0, cv.width, cv.height).data;
    const lum = [];
    for (let i = 0; i < px.length; i += 4 * 7) lum.push(0.299 * px[i] + 0.587 * px[i + 1] + 0.114 * px[i + 2]);
    const mean = lum.reduce((a, b) => a + b, 0) / lum.length;
    const sd = Math.sqrt(lum.reduce((a, b) => a + (b - mean) ** 2, 0) / lum.length);
    const levels = new Set(lum.map((l) => Math.round(l))).size;
    return { loaded: v.scene.globe.tilesLoaded, h, sd, levels };
  }, { lon: p.lon, lat: p.lat });
  fs.mkdirSync(path.dirname(screenshot), { recursive: true });
  await page.screenshot({ path: screenshot });
  console.log(`# view: ${JSON.stringify(stats)}; screenshot ${screenshot}`);
  assert.ok(stats.loaded, 'tiles never finished loading');
  const ref = D.at(p.lon + 0.5, p.lat + 0.5);
  assert.ok(stats.h !== undefined && Math.abs(stats.h - ref) < 300, `globe height ${stats.h} vs DEM ${ref}`);
  assert.ok(stats.sd > 8 && stats.levels > 40, `the view looks flat: ${JSON.stringify(stats)}`);
  assert.deepEqual(errors, []);
});
