// The browser side of three3d.test.mjs, bundled by esbuild when that test
// runs: 3DTilesRendererJS (npm `3d-tiles-renderer`) drawing a `cota tiles
// --format 3dtiles` tileset in three.js, and the decode timings of GLB and
// quantized-mesh tiles. Sets window.render3d and window.decodeBench.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';
import { TilesRenderer } from '3d-tiles-renderer/three';
import { ImplicitTilingPlugin, QuantizedMeshLoaderBase } from '3d-tiles-renderer/core/plugins';
import { GLTFExtensionsPlugin } from '3d-tiles-renderer/three/plugins';
import { QuantizedMeshLoader } from '3d-tiles-renderer/src/three/plugins/loaders/QuantizedMeshLoader.js';

const RAD = Math.PI / 180;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

const canvas = document.createElement('canvas');
document.body.appendChild(canvas);
const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true, logarithmicDepthBuffer: true });
renderer.setPixelRatio(1);
renderer.setSize(800, 600);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x000000);
scene.add(new THREE.AmbientLight(0xffffff, 0.35));
const sun = new THREE.DirectionalLight(0xffffff, 2.2);
scene.add(sun, sun.target);
const camera = new THREE.PerspectiveCamera(60, 800 / 600, 1, 2e7);
// The GLBs carry no material, and glTF's default (metallic 1) shows no diffuse
// light without an environment: a matt one, as an application would set.
const ground = new THREE.MeshStandardMaterial({ color: 0xd9cdb4, metalness: 0, roughness: 1 });

let tiles = null;
const events = { errors: [], models: [], subtrees: 0 };

/**
 * Loads `url` (tileset.json) with TilesRenderer and the implicit tiling and
 * glTF (meshopt) plugins, puts the camera `height` metres above (lon, lat)
 * looking at the ground point (lookLon, lookLat), and renders until no tile
 * has been queued, downloading or parsing on 5 frames running (at most
 * `limitMs`). Returns what was drawn: the visible tiles' levels, meshes and
 * triangles, the levels ever loaded, errors, the time taken.
 */
window.render3d = async ({ url, lon, lat, height, lookLon, lookLat, lookHeight = 0, errorTarget = 16, limitMs = 60000 }) => {
  if (!tiles) {
    tiles = new TilesRenderer(url);
    tiles.registerPlugin(new ImplicitTilingPlugin());
    tiles.registerPlugin(new GLTFExtensionsPlugin({ meshoptDecoder: MeshoptDecoder }));
    tiles.addEventListener('load-error', (e) => events.errors.push(`load-error ${e.url}: ${e.error && e.error.message}`));
    tiles.addEventListener('load-model', (e) => {
      let triangles = 0;
      e.scene.traverse((o) => {
        if (!o.isMesh) return;
        o.material = ground;
        triangles += o.geometry.index ? o.geometry.index.count / 3 : 0;
      });
      events.models.push({ level: e.tile.implicitTilingData ? e.tile.implicitTilingData.level : -1, triangles });
    });
    scene.add(tiles.group);
  }
  tiles.errorTarget = errorTarget;
  const ell = tiles.ellipsoid;
  const eye = ell.getCartographicToPosition(lat * RAD, lon * RAD, height, new THREE.Vector3());
  const at = ell.getCartographicToPosition(lookLat * RAD, lookLon * RAD, lookHeight, new THREE.Vector3());
  ell.getCartographicToNormal(lat * RAD, lon * RAD, camera.up);
  camera.position.copy(eye);
  camera.lookAt(at);
  camera.near = Math.max(1, height / 100);
  camera.far = 2e7;
  camera.updateProjectionMatrix();
  camera.updateMatrixWorld();
  // A low sun (about 20° up) from the west-south-west of the ground point.
  const up = ell.getCartographicToNormal(lat * RAD, lon * RAD, new THREE.Vector3());
  const east = new THREE.Vector3(-Math.sin(lon * RAD), Math.cos(lon * RAD), 0);
  const north = new THREE.Vector3().crossVectors(up, east);
  sun.position.copy(at).addScaledVector(up, 3e5).addScaledVector(east, -8e5).addScaledVector(north, -2e5);
  sun.target.position.copy(at);
  sun.target.updateMatrixWorld();
  tiles.setCamera(camera);
  tiles.setResolutionFromRenderer(camera, renderer);
  const t0 = performance.now();
  let idle = 0;
  while (performance.now() - t0 < limitMs && idle < 5) {
    camera.updateMatrixWorld();
    tiles.update();
    renderer.render(scene, camera);
    const s = tiles.stats;
    const busy = !tiles.rootTileset || tiles.isLoading || s.queued + s.downloading + s.parsing > 0;
    idle = busy ? 0 : idle + 1;
    await sleep(30);
  }
  renderer.render(scene, camera);
  const visible = {};
  const uris = [];
  let meshes = 0;
  let triangles = 0;
  for (const t of tiles.visibleTiles) {
    const sceneOf = t.engineData && t.engineData.scene;
    if (!sceneOf) continue;
    const level = t.implicitTilingData ? t.implicitTilingData.level : -1;
    visible[level] = (visible[level] || 0) + 1;
    uris.push(t.content.uri);
    sceneOf.traverse((o) => {
      if (o.isMesh && o.geometry.attributes.position && o.geometry.attributes.position.count > 0) {
        meshes++;
        triangles += o.geometry.index ? o.geometry.index.count / 3 : 0;
      }
    });
  }
  const loadedLevels = [...new Set(events.models.map((m) => m.level))].sort((a, b) => a - b);
  return {
    done: idle >= 5, uris: uris.sort(), ms: Math.round(performance.now() - t0), visible, meshes, triangles, loadedLevels,
    models: events.models.length, errors: events.errors.slice(), stats: { ...tiles.stats },
  };
};

/** The canvas's pixels: the fraction not background (black), and the lit pixels' luminance spread. */
window.pixels = () => {
  const gl = renderer.getContext();
  const [w, h] = [gl.drawingBufferWidth, gl.drawingBufferHeight];
  const px = new Uint8Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  let terrain = 0;
  let terrainLower = 0;
  const lum = [];
  for (let i = 0; i < px.length; i += 4) {
    if (Math.max(px[i], px[i + 1], px[i + 2]) <= 8) continue;
    terrain++;
    // readPixels rows run from the bottom: the lower half of the view comes first.
    if (i < px.length / 2) terrainLower++;
    lum.push(0.299 * px[i] + 0.587 * px[i + 1] + 0.114 * px[i + 2]);
  }
  const mean = lum.reduce((a, b) => a + b, 0) / Math.max(1, lum.length);
  const sd = Math.sqrt(lum.reduce((a, b) => a + (b - mean) ** 2, 0) / Math.max(1, lum.length));
  return { terrain: terrain / (w * h), terrainLower: terrainLower / (w * h / 2), sd, levels: new Set(lum.map(Math.round)).size };
};

/**
 * The fraction of the canvas's pixels whose ray from the camera meets the
 * WGS 84 ellipsoid: what a plain globe (terrain everywhere, no holes) covers
 * in the last view.
 */
window.globeFraction = () => {
  const [w, h] = [800, 600];
  const [a, b] = [6378137, 6356752.314245179];
  const o = camera.position;
  const p = new THREE.Vector3();
  let hits = 0;
  for (let j = 0; j < h; j++) {
    for (let i = 0; i < w; i++) {
      p.set(((i + 0.5) / w) * 2 - 1, 1 - ((j + 0.5) / h) * 2, 0.5).unproject(camera).sub(o);
      // The ray o + t·d in coordinates scaled to the unit sphere.
      const [ox, oy, oz] = [o.x / a, o.y / a, o.z / b];
      const [dx, dy, dz] = [p.x / a, p.y / a, p.z / b];
      const B = ox * dx + oy * dy + oz * dz;
      const A = dx * dx + dy * dy + dz * dz;
      const C = ox * ox + oy * oy + oz * oz - 1;
      if (B < 0 && B * B - A * C >= 0) hits++;
    }
  }
  return hits / (w * h);
};

// ---- Decode timings.

/** A GLB's JSON and binary chunk. */
function glbChunks(buf) {
  const dv = new DataView(buf);
  if (dv.getUint32(0, true) !== 0x46546c67) throw new Error('not a GLB');
  const jsonLen = dv.getUint32(12, true);
  const json = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 20, jsonLen)));
  const binAt = 20 + jsonLen;
  const bin = binAt + 8 <= buf.byteLength ? new Uint8Array(buf, binAt + 8, dv.getUint32(binAt, true)) : new Uint8Array(0);
  return { json, bin };
}

/** GLB to typed arrays: every bufferView an accessor uses, meshopt-decoded where compressed. */
function glbToArrays(buf) {
  const { json, bin } = glbChunks(buf);
  const out = [];
  for (const a of json.accessors) {
    const v = json.bufferViews[a.bufferView];
    const m = v.extensions && v.extensions.EXT_meshopt_compression;
    if (m) {
      const target = new Uint8Array(m.count * m.byteStride);
      const src = bin.subarray(m.byteOffset || 0, (m.byteOffset || 0) + m.byteLength);
      MeshoptDecoder.decodeGltfBuffer(target, m.count, m.byteStride, src, m.mode, m.filter);
      out.push(target);
    } else {
      out.push(bin.subarray((v.byteOffset || 0) + (a.byteOffset || 0), (v.byteOffset || 0) + v.byteLength));
    }
  }
  return out;
}

/** [west, south, east, north] radians of a geographic TMS tile. */
function tileRect(z, x, y) {
  const size = Math.PI / 2 ** z;
  return [-Math.PI + x * size, -Math.PI / 2 + y * size, -Math.PI + (x + 1) * size, -Math.PI / 2 + (y + 1) * size];
}

const gltf = new GLTFLoader();
gltf.setMeshoptDecoder(MeshoptDecoder);
const qmBase = new QuantizedMeshLoaderBase();
const qmThree = new QuantizedMeshLoader();

/**
 * Times decoding every tile of each set ({name, kind: 'glb' | 'terrain',
 * pack, files: [{path, z, x, y, length}]}): the files are fetched first (not timed),
 * then each stage runs over all of them `rounds` times; per stage the
 * fastest round's total milliseconds. Stages: 'arrays' (GLB: JSON and
 * meshopt to typed arrays; quantized-mesh: 3DTilesRendererJS's
 * QuantizedMeshLoaderBase.parse) and 'three' (a three.js mesh: GLTFLoader;
 * 3DTilesRendererJS's QuantizedMeshLoader, skirts and ECEF positions).
 */
window.decodeBench = async (sets, rounds = 3) => {
  await MeshoptDecoder.ready;
  const out = [];
  for (const set of sets) {
    // Every tile in one response (the server concatenates them, inflated;
    // set.files carries each one's length), each copied to its own buffer.
    const r = await fetch(set.pack);
    if (!r.ok) throw new Error(`${set.pack}: ${r.status}`);
    const all = new Uint8Array(await r.arrayBuffer());
    const bufs = [];
    let bytes = 0;
    for (const f of set.files) {
      bufs.push({ b: all.slice(bytes, bytes + f.length).buffer, f });
      bytes += f.length;
    }
    if (bytes !== all.length) throw new Error(`${set.pack}: ${all.length} bytes, the index says ${bytes}`);
    const stages = set.kind === 'glb'
      ? {
        arrays: async ({ b }) => glbToArrays(b),
        three: async ({ b }) => gltf.parseAsync(b, ''),
      }
      : {
        arrays: async ({ b }) => qmBase.parse(b),
        three: async ({ b, f }) => {
          [qmThree.minLon, qmThree.minLat, qmThree.maxLon, qmThree.maxLat] = tileRect(f.z, f.x, f.y);
          return qmThree.parse(b);
        },
      };
    const result = { name: set.name, tiles: bufs.length, bytes };
    for (const [stage, fn] of Object.entries(stages)) {
      let best = Infinity;
      for (let k = 0; k < rounds; k++) {
        const t0 = performance.now();
        for (const item of bufs) {
          const r = await fn(item);
          if (!r) throw new Error(`${set.name} ${item.f.path}: nothing decoded`);
        }
        best = Math.min(best, performance.now() - t0);
      }
      result[stage] = best;
    }
    out.push(result);
  }
  return out;
};

window.pageReady = true;
