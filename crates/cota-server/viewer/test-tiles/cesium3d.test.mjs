// CesiumJS's 3D Tiles terrain provider (Cesium3DTilesTerrainProvider, the npm
// `cesium` package) in headless Debian Chromium over a `cota tiles --format
// 3dtiles` pyramid served by a local static server:
//  * the provider loads tileset.json, the subtrees and the GLBs without error;
//  * sampleTerrain at the finest zoom agrees with the DEM at DEM samples within
//    that zoom's bound e_Z (from the run's --json report; float32's rounding,
//    under a millimetre at these zooms, is allowed on top);
//  * rendered: a few km up over the data (shaded relief, no holes), and from
//    12,000 km the globe's outline within 2 percentage points of black pixels of
//    the same view over EllipsoidTerrainProvider (no tile cuts through the globe).
// Environment: COTA_TILES3D (the pyramid), COTA_TILES_DEM (the SRTM files it was
// made from), COTA_TILES3D_REPORT (`cota tiles --format 3dtiles --json`),
// COTA_TILES3D_SCREENSHOT (default target/tiles3d-cesium.png; -12000km,
// -12000km-ellipsoid and -ground beside it).
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { readDem, footprint } from './common.mjs';

const dir = process.env.COTA_TILES3D;
const demFiles = (process.env.COTA_TILES_DEM || '').split(',').filter(Boolean);
const reportPath = process.env.COTA_TILES3D_REPORT;
if (!dir || demFiles.length === 0 || !reportPath) {
  throw new Error('set COTA_TILES3D, COTA_TILES_DEM and COTA_TILES3D_REPORT (see .ci/run)');
}
const here = path.dirname(fileURLToPath(import.meta.url));
const cesiumDir = path.join(here, '..', 'node_modules', 'cesium', 'Build', 'Cesium');
const screenshot = process.env.COTA_TILES3D_SCREENSHOT || path.join(here, '..', '..', '..', '..', 'target', 'tiles3d-cesium.png');
const shot = (tag) => screenshot.replace(/(\.png)?$/, `-${tag}.png`);
const report = JSON.parse(fs.readFileSync(reportPath, 'utf8'));
const last = report.zooms[report.zooms.length - 1];
const maxZoom = last.zoom;
const bound = last.max_error_m;
const D = readDem(demFiles);
const FP = footprint(D);

const TYPES = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8',
  '.json': 'application/json',
  '.glb': 'model/gltf-binary',
  '.subtree': 'application/octet-stream',
  '.png': 'image/png',
  '.svg': 'image/svg+xml',
  '.wasm': 'application/wasm',
};

const PAGE = `<!doctype html><html><head><meta charset="utf-8">
<link rel="stylesheet" href="/cesium/Widgets/widgets.css">
<style>html,body,#c{margin:0;width:100%;height:100%;overflow:hidden}</style>
<script>window.CESIUM_BASE_URL = '/cesium/';</script>
<script src="/cesium/Cesium.js"></script></head><body><div id="c"></div></body></html>`;

const requested = { glb: 0, subtree: 0, missing: [] };
function serve(root, base, res) {
  const file = path.normalize(path.join(root, base));
  if (!file.startsWith(root) || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
    if (root !== cesiumDir) requested.missing.push(base);
    res.writeHead(404).end();
    return;
  }
  if (file.endsWith('.glb')) requested.glb++;
  if (file.endsWith('.subtree')) requested.subtree++;
  res.writeHead(200, { 'Content-Type': TYPES[path.extname(file)] || 'application/octet-stream' }).end(fs.readFileSync(file));
}

const server = http.createServer((req, res) => {
  const p = decodeURIComponent(new URL(req.url, 'http://localhost').pathname);
  if (p === '/') res.writeHead(200, { 'Content-Type': TYPES['.html'] }).end(PAGE);
  else if (p.startsWith('/cesium/')) serve(cesiumDir, p.slice('/cesium/'.length), res);
  else if (p.startsWith('/tiles/')) serve(path.resolve(dir), p.slice('/tiles/'.length), res);
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
const logs = [];
page.on('pageerror', (e) => errors.push(String(e)));
page.on('console', (m) => { if (/Could not load/.test(m.text())) logs.push(m.text()); });
await page.goto(origin + '/');
await page.waitForFunction(() => typeof window.Cesium !== 'undefined');
await page.evaluate(async () => {
  const C = window.Cesium;
  const terrainProvider = await C.Cesium3DTilesTerrainProvider.fromUrl('/tiles/tileset.json', { requestVertexNormals: true });
  const viewer = new C.Viewer('c', {
    terrainProvider, baseLayer: false, animation: false, timeline: false, baseLayerPicker: false,
    geocoder: false, homeButton: false, sceneModePicker: false, navigationHelpButton: false,
    fullscreenButton: false, infoBox: false, selectionIndicator: false, skyBox: false,
    skyAtmosphere: false, contextOptions: { webgl: { preserveDrawingBuffer: true } },
  });
  viewer.scene.globe.baseColor = C.Color.WHITE;
  window.viewer = viewer;
  window.terrainProvider = terrainProvider;
  window.show = async ({ lon, lat, height, heading = 0, pitch = -90, lit = false }) => {
    const v = window.viewer;
    const g = v.scene.globe;
    g.enableLighting = lit;
    g.showGroundAtmosphere = lit;
    v.scene.fog.enabled = lit;
    const d = new C.Cartesian3(1, 1, -0.3);
    v.scene.light = new C.DirectionalLight({ direction: C.Cartesian3.normalize(d, d) });
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
    return { black: black / (px.length / 4), blackBelow: blackBelow / (px.length / 8), sd, levels: new Set(lum.map(Math.round)).size };
  };
});
after(async () => {
  await browser.close();
  server.close();
});

async function capture(view, file) {
  const r = await page.evaluate((v) => window.show(v), view);
  assert.ok(r.loaded, `tiles never finished loading for ${JSON.stringify(view)}`);
  const stats = await page.evaluate(() => window.pixels());
  fs.mkdirSync(path.dirname(file), { recursive: true });
  await page.screenshot({ path: file });
  console.log(`# ${JSON.stringify(view)}: black ${(100 * stats.black).toFixed(2)} %, luminance sd ${stats.sd.toFixed(1)}, ${stats.levels} levels, ${r.ms} ms; screenshot ${file}`);
  return stats;
}

test('sampleTerrain at the finest zoom agrees with the DEM at DEM samples within e_Z', async () => {
  const pts = [];
  for (const p of D.parts) {
    for (let j = 0; j <= 20; j++) for (let i = 0; i <= 20; i++) {
      const [c, r] = [Math.round((i / 20) * (p.n - 1)), Math.round((j / 20) * (p.n - 1))];
      const h = p.h[r * p.n + c];
      if (h !== -32768) pts.push({ lon: p.lon + c / (p.n - 1), lat: p.lat + 1 - r / (p.n - 1), h });
    }
  }
  const got = await page.evaluate(async ({ pts, z }) => {
    const C = window.Cesium;
    const carto = pts.map((q) => C.Cartographic.fromDegrees(q.lon, q.lat));
    const out = await C.sampleTerrain(window.terrainProvider, z, carto, true);
    return out.map((c) => c.height);
  }, { pts, z: maxZoom });
  let worst = 0;
  const bad = [];
  pts.forEach((q, k) => {
    const d = Math.abs(got[k] - q.h);
    worst = Math.max(worst, d);
    if (!(d <= bound + 1e-3)) bad.push(`${q.lon},${q.lat}: Cesium ${got[k]}, DEM ${q.h}`);
  });
  assert.ok(pts.length > 400, `only ${pts.length} points`);
  console.log(`# ${pts.length} DEM samples at zoom ${maxZoom}: largest |Cesium − DEM| ${worst.toFixed(3)} m, e_${maxZoom} ${bound.toFixed(3)} m`);
  assert.deepEqual(bad, [], `beyond e_${maxZoom} = ${bound}`);
  assert.deepEqual(errors, []);
  assert.deepEqual(logs, []);
});

test('near the ground over the data: shaded relief, no holes', async () => {
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
  const stats = await capture({ lon: best.lon, lat: best.lat - 0.045, height: best.h + 2000, pitch: -15, lit: true }, shot('ground'));
  assert.equal(stats.blackBelow, 0, 'black pixels (holes) in the lower half of the view');
  assert.ok(stats.sd > 8 && stats.levels > 40, `the view looks flat: ${JSON.stringify(stats)}`);
  assert.deepEqual(errors, []);
  assert.deepEqual(logs, []);
});

test("from 12,000 km the globe's outline matches the ellipsoid's (black pixels within 2 points)", async () => {
  const p = D.parts[0];
  const view = { lon: p.lon + 0.5, lat: p.lat + 0.5, height: 12e6 };
  const cota = await capture(view, shot('12000km'));
  await page.evaluate(() => { window.viewer.scene.terrainProvider = new window.Cesium.EllipsoidTerrainProvider(); });
  const ellipsoid = await capture(view, shot('12000km-ellipsoid'));
  await page.evaluate(() => { window.viewer.scene.terrainProvider = window.terrainProvider; });
  const gap = 100 * Math.abs(cota.black - ellipsoid.black);
  console.log(`# 12000km: black ${(100 * cota.black).toFixed(2)} % over cota's 3D Tiles, ${(100 * ellipsoid.black).toFixed(2)} % over the ellipsoid (${gap.toFixed(2)} points apart)`);
  assert.ok(ellipsoid.black > 0.05 && ellipsoid.black < 0.95);
  assert.ok(gap <= 2, `${gap} points apart`);
  console.log(`# requests: ${requested.glb} GLB, ${requested.subtree} subtrees, ${requested.missing.length} missing`);
  assert.ok(requested.glb > 10 && requested.subtree >= 2);
  assert.deepEqual(requested.missing, [], 'the client asked for files the pyramid does not have');
  assert.deepEqual(errors, []);
  assert.deepEqual(logs, []);
});
