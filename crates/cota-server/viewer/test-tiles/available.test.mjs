// Which tiles a cota pyramid holds: layer.json's `available` lists exactly
// the tile files in the directory, every tile but the two zoom-0 roots
// shares a positive area with the DEM's footprint (no tile wholly beyond
// the data), and every tile that does is written (the data are covered at
// every zoom). The footprint is the SRTM files' own extent, not layer.json's.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { requireEnv, tilesDir, layer, tiles, rect, dem, footprint, sharedArea } from './common.mjs';

requireEnv();
const L = layer();
const FP = footprint(dem());
const key = (t) => `${t.z}/${t.x}/${t.y}`;

/** Every `{z}/{x}/{y}.terrain` file under the pyramid's directory. */
function files() {
  const out = [];
  for (const z of fs.readdirSync(tilesDir)) {
    const dz = path.join(tilesDir, z);
    if (!/^\d+$/.test(z) || !fs.statSync(dz).isDirectory()) continue;
    for (const x of fs.readdirSync(dz)) {
      for (const f of fs.readdirSync(path.join(dz, x))) {
        const m = /^(\d+)\.terrain$/.exec(f);
        assert.ok(m, `unexpected file ${z}/${x}/${f}`);
        out.push(`${z}/${x}/${m[1]}`);
      }
    }
  }
  return out;
}

test("layer.json's available lists exactly the tile files present", () => {
  const listed = [...tiles(L)].map(key);
  assert.equal(new Set(listed).size, listed.length, 'a tile listed twice');
  const present = files();
  const missing = listed.filter((k) => !present.includes(k));
  const unlisted = present.filter((k) => !listed.includes(k));
  assert.deepEqual(missing, [], 'listed in available, no file');
  assert.deepEqual(unlisted, [], 'a file not listed in available');
  assert.equal(L.minzoom, 0);
  assert.equal(L.available.length, L.maxzoom + 1, 'one entry of available per zoom');
  console.log(`# ${listed.length} tiles listed and present over zooms 0…${L.maxzoom}`);
});

test('no tile lies wholly outside the data (but the zoom-0 roots), and every tile over the data is written', () => {
  const listed = new Set([...tiles(L)].map(key));
  for (const t of tiles(L)) {
    if (t.z === 0) continue;
    const a = sharedArea(FP, rect(t));
    assert.ok(a > 0, `${key(t)} [${rect(t)}] shares no area with the DEM's footprint ${JSON.stringify(FP)}`);
  }
  assert.ok(listed.has('0/0/0') && listed.has('0/1/0'), 'both zoom-0 root tiles are written (CesiumJS needs them)');
  const perZoom = [];
  for (let z = 0; z <= L.maxzoom; z++) {
    // The tiles of zoom z whose rectangles meet the footprint with positive area.
    const size = 180 / 2 ** z;
    const over = new Set();
    for (const [w, s, e, nn] of FP) {
      for (let y = Math.floor((s + 90) / size); y < Math.ceil((nn + 90) / size); y++) {
        for (let x = Math.floor((w + 180) / size); x < Math.ceil((e + 180) / size); x++) {
          const t = { z, x, y };
          if (sharedArea(FP, rect(t)) > 0) {
            assert.ok(listed.has(key(t)), `${key(t)} covers data but is not written`);
            over.add(key(t));
          }
        }
      }
    }
    perZoom.push(over.size);
  }
  console.log(`# tiles over the data per zoom: ${perZoom.join(' ')}`);
});
