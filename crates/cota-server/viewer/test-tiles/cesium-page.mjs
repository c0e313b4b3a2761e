// CesiumJS (the npm `cesium` package) in headless Debian Chromium over a cota
// pyramid on a local static server: shared by cesium.test.mjs (quantized-mesh,
// CesiumTerrainProvider) and cesium3d.test.mjs (3D Tiles terrain,
// Cesium3DTilesTerrainProvider).
import assert from 'node:assert/strict';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = path.dirname(fileURLToPath(import.meta.url));
const cesiumDir = path.join(here, '..', 'node_modules', 'cesium', 'Build', 'Cesium');

const TYPES = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8',
  '.json': 'application/json',
  '.terrain': 'application/vnd.quantized-mesh',
  '.glb': 'model/gltf-binary',
  '.subtree': 'application/octet-stream',
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

/**
 * Opens CesiumJS over the pyramid in `tilesDir` (served at /tiles/; gzipped
 * .terrain tiles with Content-Encoding) with the terrain provider `provider`
 * ('quantized-mesh' or '3dtiles'). Returns the page, the page errors seen,
 * the pyramid's files served and asked for but missing, and `close`.
 */
export async function openCesium(tilesDir, provider) {
  const root = path.resolve(tilesDir);
  const requested = { files: [], missing: [] };
  const serve = (dir, base, res) => {
    const file = path.normalize(path.join(dir, base));
    if (!file.startsWith(dir) || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
      if (dir === root) requested.missing.push(base);
      res.writeHead(404).end();
      return;
    }
    if (dir === root) requested.files.push(base);
    const bytes = fs.readFileSync(file);
    const headers = { 'Content-Type': TYPES[path.extname(file)] || 'application/octet-stream' };
    if (bytes[0] === 0x1f && bytes[1] === 0x8b && file.endsWith('.terrain')) headers['Content-Encoding'] = 'gzip';
    res.writeHead(200, headers).end(bytes);
  };
  const server = http.createServer((req, res) => {
    const p = decodeURIComponent(new URL(req.url, 'http://localhost').pathname);
    if (p === '/') res.writeHead(200, { 'Content-Type': TYPES['.html'] }).end(PAGE);
    else if (p.startsWith('/cesium/')) serve(cesiumDir, p.slice('/cesium/'.length), res);
    else if (p.startsWith('/tiles/')) serve(root, p.slice('/tiles/'.length), res);
    else res.writeHead(404).end();
  });
  await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--enable-unsafe-swiftshader'],
  });
  const page = await browser.newPage({ viewport: { width: 800, height: 600 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  // Cesium3DTilesTerrainProvider reports a tile it could not load on the console only.
  page.on('console', (m) => { if (/Could not load/.test(m.text())) errors.push(m.text()); });
  await page.goto(`http://127.0.0.1:${server.address().port}/`);
  await page.waitForFunction(() => typeof window.Cesium !== 'undefined');
  await page.evaluate(setUpPage, provider);
  const close = async () => {
    await browser.close();
    server.close();
  };
  return { page, errors, requested, close };
}

/** Runs in the page: the viewer over the provider, and window.show / window.pixels. */
async function setUpPage(provider) {
  const C = window.Cesium;
  const terrainProvider = provider === '3dtiles'
    ? await C.Cesium3DTilesTerrainProvider.fromUrl('/tiles/tileset.json', { requestVertexNormals: true })
    : await C.CesiumTerrainProvider.fromUrl('/tiles/', {
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
}

/** Shows the view, checks that its tiles loaded, saves the screenshot; the pixels' figures. */
export async function capture(page, view, file) {
  const r = await page.evaluate((v) => window.show(v), view);
  assert.ok(r.loaded, `tiles never finished loading for ${JSON.stringify(view)}`);
  const stats = await page.evaluate(() => window.pixels());
  fs.mkdirSync(path.dirname(file), { recursive: true });
  await page.screenshot({ path: file });
  console.log(`# ${JSON.stringify(view)}: black ${(100 * stats.black).toFixed(2)} %, luminance sd ${stats.sd.toFixed(1)}, ${stats.levels} levels, ${r.ms} ms; screenshot ${file}`);
  return stats;
}

/**
 * The view over cota's terrain (screenshot `file`) and over CesiumJS's
 * ellipsoid (`-ellipsoid` beside it): black fractions within 2 percentage points.
 */
export async function againstEllipsoid(page, view, file, tag) {
  const cota = await capture(page, view, file);
  await page.evaluate(() => { window.viewer.scene.terrainProvider = new window.Cesium.EllipsoidTerrainProvider(); });
  let ellipsoid;
  try {
    ellipsoid = await capture(page, view, file.replace(/\.png$/, '-ellipsoid.png'));
  } finally {
    await page.evaluate(() => { window.viewer.scene.terrainProvider = window.terrainProvider; });
  }
  const gap = 100 * Math.abs(cota.black - ellipsoid.black);
  console.log(`# ${tag}: black pixels ${(100 * cota.black).toFixed(2)} % over cota's tiles, ${(100 * ellipsoid.black).toFixed(2)} % over the ellipsoid (${gap.toFixed(2)} points apart)`);
  assert.ok(ellipsoid.black > 0.05 && ellipsoid.black < 0.95, `the ellipsoid view should show both globe and space: ${ellipsoid.black}`);
  assert.ok(gap <= 2, `${tag}: ${(100 * cota.black).toFixed(2)} % black over cota's tiles vs ${(100 * ellipsoid.black).toFixed(2)} % over the ellipsoid`);
}

/** The highest DEM sample at least 0.15° inside the footprint `fp` (every other sample of `dem`). */
export function highestInside(dem, fp) {
  let best = { h: -Infinity };
  for (const p of dem.parts) {
    for (let r = 0; r < p.n; r += 2) {
      for (let c = 0; c < p.n; c += 2) {
        const [lon, lat] = [p.lon + c / (p.n - 1), p.lat + 1 - r / (p.n - 1)];
        const inner = fp.some(([w, s, e, n]) => lon - w >= 0.15 && e - lon >= 0.15 && lat - s >= 0.15 && n - lat >= 0.15);
        if (inner && p.h[r * p.n + c] > best.h) best = { h: p.h[r * p.n + c], lon, lat };
      }
    }
  }
  return best;
}

/** DEM samples (exactly at their positions) on a 21 × 21 grid over each SRTM tile, its edges included. */
export function demSamples(dem) {
  const pts = [];
  for (const p of dem.parts) {
    for (let j = 0; j <= 20; j++) for (let i = 0; i <= 20; i++) {
      const [c, r] = [Math.round((i / 20) * (p.n - 1)), Math.round((j / 20) * (p.n - 1))];
      const h = p.h[r * p.n + c];
      if (h !== -32768) pts.push({ lon: p.lon + c / (p.n - 1), lat: p.lat + 1 - r / (p.n - 1), h });
    }
  }
  return pts;
}
