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
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { requireEnv, tilesDir, layer, bounds, dem, footprint, outside, tileDeg } from './common.mjs';
import { openCesium, capture as captureOn, againstEllipsoid as againstEllipsoidOn, highestInside, demSamples } from './cesium-page.mjs';

requireEnv();
const here = path.dirname(fileURLToPath(import.meta.url));
const screenshot = process.env.COTA_TILES_SCREENSHOT || path.join(here, '..', '..', '..', '..', 'target', 'tiles-cesium.png');
const L = layer();
const maxZoom = L.maxzoom;
const bound = bounds(L).get(maxZoom).maxError;
const D = dem();
const FP = footprint(D);
/** The name of a screenshot beside the main one. */
const shot = (tag) => screenshot.replace(/(\.png)?$/, `-${tag}.png`);

const { page, errors, close } = await openCesium(tilesDir, 'quantized-mesh');
after(close);
const capture = (view, file) => captureOn(page, view, file);

/** The view over cota's terrain and over CesiumJS's ellipsoid: black fractions within 2 percentage points. */
async function againstEllipsoid(view, tag) {
  await againstEllipsoidOn(page, view, shot(tag), tag);
  assert.deepEqual(errors, []);
}

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

test('sampleTerrainMostDetailed agrees with the DEM at DEM samples within e_Z', async () => {
  const pts = demSamples(D);
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
  const best = highestInside(D, FP);
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
