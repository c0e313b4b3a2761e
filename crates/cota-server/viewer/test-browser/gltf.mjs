// three.js's GLTFLoader in headless Debian chromium over GLB files written by
// cota (plain, quantized, strip, textured pair): each must load without an
// error or a console error, hold at least one mesh with positions and
// indices, and, when textured (`cota pair`, `cota mesh --texture`), a
// TEXCOORD_0 attribute in [0, 1] and a decoded image of non-zero size on an
// unlit material. The page is served from a throwaway loopback server: the
// three.js module files of this package and the GLBs, nothing else.
// Usage: node test-browser/gltf.mjs FILE.glb... (CHROMIUM: default /usr/bin/chromium)
import { chromium } from 'playwright-core';
import { createServer } from 'node:http';
import { readFileSync, statSync } from 'node:fs';
import { basename, dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const three = join(here, '../node_modules/three');
const files = process.argv.slice(2).map((f) => resolve(f));
if (files.length === 0) {
  console.error('usage: node test-browser/gltf.mjs FILE.glb...');
  process.exit(2);
}
const ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--enable-unsafe-swiftshader'];

const PAGE = `<!doctype html><meta charset="utf-8">
<script type="importmap">{"imports":{"three":"/three/build/three.module.js","three/addons/":"/three/examples/jsm/"}}</script>
<script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
window.load = (url) => new Promise((res) => new GLTFLoader().load(url, (gltf) => {
  const meshes = [];
  gltf.scene.traverse((o) => {
    if (!o.isMesh) return;
    const g = o.geometry, uv = g.getAttribute('uv'), m = o.material;
    let uvMin = Infinity, uvMax = -Infinity;
    if (uv) for (let i = 0; i < uv.count; i++) {
      for (const v of [uv.getX(i), uv.getY(i)]) { uvMin = Math.min(uvMin, v); uvMax = Math.max(uvMax, v); }
    }
    const img = m.map && m.map.image;
    meshes.push({
      vertices: g.getAttribute('position').count, indices: g.index ? g.index.count : 0,
      uv: !!uv, uvMin, uvMax, unlit: m.type === 'MeshBasicMaterial',
      image: img ? [img.width, img.height] : null,
    });
  });
  res({ ok: true, meshes });
}, undefined, (e) => res({ ok: false, error: String(e && e.message || e) })));
window.ready = true;
</script>`;

const mime = { '.js': 'text/javascript', '.glb': 'model/gltf-binary', '.html': 'text/html' };
const server = createServer((req, res) => {
  const url = decodeURIComponent(req.url.split('?')[0]);
  let path = null;
  if (url === '/') path = null;
  else if (url.startsWith('/three/') && !url.includes('..')) path = join(three, url.slice('/three/'.length));
  else if (url.startsWith('/glb/')) path = files.find((f) => basename(f) === url.slice(5)) || '';
  if (path === null) {
    res.writeHead(200, { 'content-type': mime['.html'] }).end(PAGE);
    return;
  }
  try {
    statSync(path);
    const ext = path.slice(path.lastIndexOf('.'));
    res.writeHead(200, { 'content-type': mime[ext] || 'application/octet-stream' }).end(readFileSync(path));
  } catch {
    res.writeHead(404).end();
  }
});
await new Promise((r) => server.listen(0, '127.0.0.1', r));
const base = `http://127.0.0.1:${server.address().port}`;
const browser = await chromium.launch({ executablePath: process.env.CHROMIUM || '/usr/bin/chromium', args: ARGS });
let failed = 0;
try {
  const page = await browser.newPage();
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(`${base}/`);
  await page.waitForFunction(() => window.ready, null, { timeout: 60000 });
  for (const f of files) {
    const r = await page.evaluate((u) => window.load(u), `/glb/${basename(f)}`);
    const problems = [];
    if (!r.ok) problems.push(r.error);
    else {
      if (r.meshes.length === 0) problems.push('no mesh');
      for (const m of r.meshes) {
        if (m.vertices < 3 || m.indices < 3 && m.indices !== 0) problems.push(`a mesh of ${m.vertices} vertices, ${m.indices} indices`);
        if (m.uv && (m.uvMin < 0 || m.uvMax > 1)) problems.push(`TEXCOORD_0 outside [0, 1]: ${m.uvMin}..${m.uvMax}`);
        if (m.uv && !(m.image && m.image[0] > 0 && m.image[1] > 0)) problems.push('TEXCOORD_0 without a decoded image');
        if (m.uv && !m.unlit) problems.push('textured but not unlit (KHR_materials_unlit)');
      }
    }
    problems.push(...errors.splice(0));
    const textured = r.ok && r.meshes.some((m) => m.uv);
    const what = r.ok ? `${r.meshes.length} mesh(es), ${r.meshes.reduce((a, m) => a + m.vertices, 0)} vertices` +
      (textured ? `, textured ${r.meshes.find((m) => m.image).image.join('×')}` : '') : '';
    if (problems.length) failed++;
    console.log(`${problems.length ? 'FAIL' : 'ok  '} GLTFLoader ${basename(f)}: ${problems.length ? problems.join('; ') : what}`);
  }
} finally {
  await browser.close();
  server.close();
}
console.log(`${files.length - failed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
