// CesiumJS's 3D Tiles terrain provider (Cesium3DTilesTerrainProvider, the npm
// `cesium` package) in headless Debian Chromium over a `cota tiles --format
// 3dtiles` pyramid served by a local static server (cesium-page.mjs):
//  * the provider loads tileset.json, the subtrees and the GLBs without error,
//    and asks for no file the pyramid does not have;
//  * sampleTerrain at the finest zoom agrees with the DEM at DEM samples within
//    that zoom's bound e_Z (from the run's --json report; float32's rounding,
//    under a millimetre at these zooms, is allowed on top);
//  * rendered: a few km up over the data (shaded relief, no holes), from 800 km
//    looking down, and from 12,000 km and 800 km at the horizon the globe's
//    outline within 2 percentage points of black pixels of the same view over
//    EllipsoidTerrainProvider (no coarse tile cuts through the globe).
// Environment: COTA_TILES3D (the pyramid), COTA_TILES_DEM (the SRTM files it was
// made from), COTA_TILES3D_REPORT (`cota tiles --format 3dtiles --json`),
// COTA_TILES3D_SCREENSHOT (default target/tiles3d-cesium.png; -ground, -800km,
// -12000km, -800km-horizon and their -ellipsoid views beside it).
// Without COTA_TILES3D (a run over a quantized-mesh pyramid only) it skips.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { readDem, footprint } from './common.mjs';
import { openCesium, capture, againstEllipsoid, highestInside, demSamples } from './cesium-page.mjs';

const dir = process.env.COTA_TILES3D;
const demFiles = (process.env.COTA_TILES_DEM || '').split(',').filter(Boolean);
const reportPath = process.env.COTA_TILES3D_REPORT;
const ready = Boolean(dir && demFiles.length > 0 && reportPath);
if (!ready) {
  test('3D Tiles terrain in CesiumJS', { skip: 'set COTA_TILES3D, COTA_TILES_DEM and COTA_TILES3D_REPORT (see .ci/run)' }, () => {});
} else {
  const here = path.dirname(fileURLToPath(import.meta.url));
  const screenshot = process.env.COTA_TILES3D_SCREENSHOT || path.join(here, '..', '..', '..', '..', 'target', 'tiles3d-cesium.png');
  const shot = (tag) => screenshot.replace(/(\.png)?$/, `-${tag}.png`);
  const report = JSON.parse(fs.readFileSync(reportPath, 'utf8'));
  const last = report.zooms[report.zooms.length - 1];
  const [maxZoom, bound] = [last.zoom, last.max_error_m];
  const D = readDem(demFiles);
  const FP = footprint(D);
  const { page, errors, requested, close } = await openCesium(dir, '3dtiles');
  after(close);

  test('sampleTerrain at the finest zoom agrees with the DEM at DEM samples within e_Z', async () => {
    const pts = demSamples(D);
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
  });

  test('near the ground over the data: shaded relief, no holes', async () => {
    const best = highestInside(D, FP);
    const view = { lon: best.lon, lat: best.lat - 0.045, height: best.h + 2000, pitch: -15, lit: true };
    const stats = await capture(page, view, shot('ground'));
    assert.equal(stats.blackBelow, 0, 'black pixels (holes) in the lower half of the view');
    assert.ok(stats.sd > 8 && stats.levels > 40, `the view looks flat: ${JSON.stringify(stats)}`);
    assert.deepEqual(errors, []);
  });

  test('from 800 km over the data: tiles loaded, no space showing through', async () => {
    const p = D.parts[0];
    const stats = await capture(page, { lon: p.lon + 0.5, lat: p.lat + 0.5, height: 8e5, lit: true }, shot('800km'));
    assert.equal(stats.black, 0, 'black pixels looking down from 800 km');
    assert.deepEqual(errors, []);
  });

  test("from 12,000 km and at the horizon from 800 km the globe's outline matches the ellipsoid's", async () => {
    const p = D.parts[0];
    await againstEllipsoid(page, { lon: p.lon + 0.5, lat: p.lat + 0.5, height: 12e6 }, shot('12000km'), '12000km');
    await againstEllipsoid(page, { lon: p.lon + 0.5, lat: p.lat - 2, height: 8e5, heading: 0, pitch: -20 }, shot('800km-horizon'), '800km-horizon');
    const glb = requested.files.filter((f) => f.endsWith('.glb')).length;
    const subtrees = requested.files.filter((f) => f.endsWith('.subtree')).length;
    console.log(`# requests: ${glb} GLB, ${subtrees} subtrees, ${requested.missing.length} missing`);
    assert.ok(glb > 10 && subtrees >= 2);
    assert.deepEqual(requested.missing, [], 'the client asked for files the pyramid does not have');
    assert.deepEqual(errors, []);
  });
}
