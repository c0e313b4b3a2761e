// loaders.gl's 3D Tiles loader (`@loaders.gl/3d-tiles` Tiles3DLoader) in node
// over a `cota tiles --format 3dtiles` pyramid served on loopback:
//  * the tileset with its implicit tiling (loaders.gl expands every subtree
//    when it parses tileset.json) names exactly the GLBs written, each at the
//    depth of its level;
//  * the largest GLB of each level parses (EXT_meshopt_compression and
//    KHR_mesh_quantization when the pyramid has --meshopt): POSITION and
//    indices of the accessors' counts, triangles indexing existing vertices,
//    positions within the accessor's min/max and reaching them.
// Environment: COTA_TILES3D (the pyramid). Without it the test skips.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { load } from '@loaders.gl/core';
import { Tiles3DLoader } from '@loaders.gl/3d-tiles';

const dir = process.env.COTA_TILES3D;

/** The GLB's JSON chunk. */
function glbJson(file) {
  const b = fs.readFileSync(file);
  return JSON.parse(b.subarray(20, 20 + b.readUInt32LE(12)).toString('utf8'));
}

if (!dir) {
  test('3D Tiles terrain in loaders.gl', { skip: 'set COTA_TILES3D (see .ci/run)' }, () => {});
} else {
  const root = path.resolve(dir);
  const server = http.createServer((req, res) => {
    const file = path.normalize(path.join(root, decodeURIComponent(new URL(req.url, 'http://localhost').pathname)));
    if (!file.startsWith(root) || !fs.existsSync(file) || !fs.statSync(file).isFile()) return res.writeHead(404).end();
    return res.writeHead(200, { 'Content-Type': 'application/octet-stream' }).end(fs.readFileSync(file));
  });
  await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
  after(() => server.close());
  const base = `http://127.0.0.1:${server.address().port}`;

  // Every GLB written: {root}/{level}/{x}/{y}.glb.
  const written = [];
  for (const r of ['0', '1']) {
    if (!fs.existsSync(path.join(root, r))) continue;
    for (const z of fs.readdirSync(path.join(root, r)).filter((n) => /^\d+$/.test(n))) {
      for (const x of fs.readdirSync(path.join(root, r, z))) {
        for (const y of fs.readdirSync(path.join(root, r, z, x))) if (y.endsWith('.glb')) written.push(`${r}/${z}/${x}/${y}`);
      }
    }
  }

  test('loaders.gl expands the implicit tiling to exactly the GLBs written, each at its level', async () => {
    const t0 = Date.now();
    const tileset = await load(`${base}/tileset.json`, Tiles3DLoader);
    const found = [];
    const wrongDepth = [];
    const walk = (t, depth) => {
      if (t.contentUrl) {
        const rel = t.contentUrl.slice(base.length + 1);
        found.push(rel);
        // Depth 0: the explicit root; depth 1: the implicit roots (level 0).
        if (Number(rel.split('/')[1]) !== depth - 1) wrongDepth.push(`${rel} at depth ${depth}`);
      }
      for (const c of t.children || []) walk(c, depth + 1);
    };
    walk(tileset.root, 0);
    console.log(`# loaders.gl: tileset and subtrees parsed in ${Date.now() - t0} ms, ${found.length} tiles with content (${written.length} GLBs written)`);
    assert.deepEqual(found.slice().sort(), written.slice().sort());
    assert.deepEqual(wrongDepth, []);
  });

  test('loaders.gl parses the largest GLB of each level: positions and triangles as the accessors say', async () => {
    // The largest GLB of each level.
    const byLevel = new Map();
    const size = (rel) => fs.statSync(path.join(root, rel)).size;
    for (const rel of written) {
      const level = Number(rel.split('/')[1]);
      if (!byLevel.has(level) || size(rel) > size(byLevel.get(level))) byLevel.set(level, rel);
    }
    for (const [level, rel] of [...byLevel].sort((a, b) => a[0] - b[0])) {
      const json = glbJson(path.join(root, rel));
      const prim = json.meshes[0].primitives[0];
      const posAcc = json.accessors[prim.attributes.POSITION];
      const idxAcc = json.accessors[prim.indices];
      const content = await load(`${base}/${rel}`, Tiles3DLoader, { '3d-tiles': { isTileset: false } });
      assert.equal(content.type, 'glTF', rel);
      const p = content.gltf.meshes[0].primitives[0];
      const pos = p.attributes.POSITION;
      const stride = pos.size || 3;
      assert.equal(pos.value.length / stride, posAcc.count, `${rel}: vertices`);
      const idx = p.indices.value;
      assert.equal(idx.length, idxAcc.count, `${rel}: indices`);
      assert.ok(idx.length > 0 && idx.length % 3 === 0, `${rel}: ${idx.length} indices`);
      assert.ok(idx.every((i) => i < posAcc.count), `${rel}: an index past the vertices`);
      if (posAcc.min && posAcc.max) {
        for (let k = 0; k < 3; k++) {
          let [lo, hi] = [Infinity, -Infinity];
          for (let i = k; i < pos.value.length; i += stride) [lo, hi] = [Math.min(lo, pos.value[i]), Math.max(hi, pos.value[i])];
          assert.ok(lo === posAcc.min[k] && hi === posAcc.max[k], `${rel}: axis ${k} spans ${lo}..${hi}, the accessor says ${posAcc.min[k]}..${posAcc.max[k]}`);
        }
      }
      console.log(`# level ${level}: ${rel}, ${posAcc.count} vertices (${pos.value.constructor.name}), ${idx.length / 3} triangles`);
    }
    assert.ok(byLevel.size > 1);
  });
}
