// Builds the viewer reproducibly from the committed package-lock.json:
// esbuild bundles src/worker.js, src/main.js (three.js) and src/cesium.js
// into content-hashed files under OUT/assets/, writes OUT/index.html and
// OUT/cesium.html, and copies CesiumJS's prebuilt files from the npm package
// into OUT/cesium/. Offline; no CDN. `node build.mjs [--outdir DIR]`
// (default dist/; cota-server's build.rs passes its OUT_DIR).
import * as esbuild from 'esbuild';
import { cpSync, mkdirSync, readFileSync, rmSync, writeFileSync, existsSync } from 'node:fs';
import { dirname, join, basename, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
const at = args.indexOf('--outdir');
const out = resolve(at >= 0 ? args[at + 1] : join(here, 'dist'));
rmSync(out, { recursive: true, force: true });
mkdirSync(join(out, 'assets'), { recursive: true });

const common = {
  bundle: true,
  minify: true,
  target: 'es2020',
  outdir: join(out, 'assets'),
  entryNames: '[name]-[hash]',
  metafile: true,
  logLevel: 'warning',
  legalComments: 'eof',
  absWorkingDir: here,
};

function outputName(result) {
  const outs = Object.keys(result.metafile.outputs).filter((f) => f.endsWith('.js'));
  return basename(outs[0]);
}

const worker = await esbuild.build({ ...common, entryPoints: ['src/worker.js'], format: 'iife' });
const workerUrl = `/assets/${outputName(worker)}`;
const main = await esbuild.build({
  ...common,
  entryPoints: ['src/main.js'],
  format: 'esm',
  define: { __COTA_WORKER__: JSON.stringify(workerUrl) },
});
const cesium = await esbuild.build({ ...common, entryPoints: ['src/cesium.js'], format: 'esm' });

const page = (file, subst) => {
  let html = readFileSync(join(here, 'src', file), 'utf8');
  for (const [k, v] of Object.entries(subst)) html = html.replace(k, v);
  writeFileSync(join(out, file), html);
};
page('index.html', { '%MAIN%': `/assets/${outputName(main)}` });
page('cesium.html', { '%CESIUM%': `/assets/${outputName(cesium)}` });

// CesiumJS ships a prebuilt, minified build: serve it as it is.
const cesiumBuild = join(here, 'node_modules/cesium/Build/Cesium');
if (!existsSync(join(cesiumBuild, 'Cesium.js'))) throw new Error(`${cesiumBuild}: run npm ci first`);
for (const part of ['Cesium.js', 'Workers', 'ThirdParty', 'Assets', 'Widgets']) {
  cpSync(join(cesiumBuild, part), join(out, 'cesium', part), { recursive: true });
}
console.log(`viewer built in ${out}`);
