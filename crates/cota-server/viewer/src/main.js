// cota's browser viewer: the progressive stream decoded in a Web Worker
// (worker.js), remeshed every frame by screen-space error (lod.js), drawn by
// three.js with a hillshade (height colours, or an image the server drapes:
// `cota serve --texture`, T switches), a wireframe toggle, an overlay of what
// it costs and a panel of the warnings the server's input gave. Positions are metres relative to the grid's centre (x east, y north,
// z up), so float32 vertices stay exact to a centimetre.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { Lod, FRAME_BUDGET_MS } from './lod.js';

/* global __COTA_WORKER__ */
const overlay = document.getElementById('overlay');
const state = {
  scripted: false,
  minClearance: Infinity,
  fly: false,
  wire: false,
  // 'height' (colours by height), 'image' (/texture.png) or 'pair' (/texture-pair.png).
  colours: 'height',
  textures: [],
  targetPx: Number(new URLSearchParams(location.search).get('px')) || 1,
  // Refinement time per frame (ms): FRAME_BUDGET_MS unless ?budget=MS.
  budgetMs: Number(new URLSearchParams(location.search).get('budget')) || FRAME_BUDGET_MS,
  received: 0,
  total: 0,
  steps: 0,
  stepsAnnounced: 0,
  lastEndOffset: 0,
  decodeMs: 0,
  done: false,
  firstDraw: null,
  refineMs: [],
  triangles: [],
  maxError: { sent: 0, all: 0 },
  t0: performance.now(),
};
const api = {
  ready: false,
  error: null,
  state,
  stats: () => stats(),
  screenError: () => (lod ? lod.maxScreenError() : null),
  setView: (eye, target) => setView(eye, target),
  release: () => {
    state.scripted = false;
  },
  frames: (n = 1) => new Promise((resolve) => waiters.push({ frame: frameNo + n, resolve })),
  pixels: () => pixels(),
  // Mean colour of the terrain pixels, and an n × n grid of mean colours over their bounding box (row 0 at the top).
  colourGrid: (n) => colourGrid(n),
  ground: (x, y) => groundZ(x, y),
  // Lowest eye height above the ground under it over the frames driven by the
  // person's controls since the last call (then reset); the default view back.
  cursorAt: (sx, sy) => {
    furniture.mouse = [sx, sy];
    furniture.moved = true;
  },
  clearance: () => {
    const c = state.minClearance;
    state.minClearance = Infinity;
    return c;
  },
  homeView: () => homeView(),
  // Mean squared luminance step between neighbouring terrain pixels of this
  // frame, with the per-vertex shading or (facets) the old per-triangle one.
  roughness: (facets) => {
    uniforms.uFacets.value = facets ? 1 : 0;
    const r = roughness();
    uniforms.uFacets.value = new URLSearchParams(location.search).has('facets') ? 1 : 0;
    return r;
  },
  fly: (on) => {
    if (state.fly !== on) toggleFly();
  },
  // Shows 'height', 'image' or 'pair' colours (those served); resolves once its texture is loaded.
  colours: (name) => setColours(name),
  // Bounding boxes of the page's panels (for tests: nothing overlaps).
  panels: () => Object.fromEntries([...document.querySelectorAll('.panel, #overlay, #controls')]
    .filter((e) => !e.hidden && e.offsetParent !== null)
    .map((e) => [e.id, e.getBoundingClientRect().toJSON()])),
};
window.cota = api;
const waiters = [];
let frameNo = 0;
let lod = null;
let meta = null;
let heights = null;
let stepOf = null;

function fail(msg) {
  api.error = msg;
  document.getElementById('error').textContent = msg;
  console.error(msg);
}

// ---- scene -----------------------------------------------------------------

const renderer = new THREE.WebGLRenderer({ antialias: true });
renderer.setPixelRatio(1);
renderer.setSize(window.innerWidth, window.innerHeight);
document.body.prepend(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x9fb8cc);
const camera = new THREE.PerspectiveCamera(60, window.innerWidth / window.innerHeight, 1, 1e6);
camera.up.set(0, 0, 1);

const uniforms = {
  uFrame: { value: 0 },
  uMorphFrames: { value: 8 },
  uSun: { value: new THREE.Vector3(-1, 1, 1.2).normalize() },
  uZRange: { value: new THREE.Vector2(0, 1000) },
  uWire: { value: 0 },
  // ?facets: the old per-triangle shading from screen-space derivatives (for comparison).
  uFacets: { value: new URLSearchParams(location.search).has('facets') ? 1 : 0 },
  // The draped texture and whether it is shown; uGrid: samples across and down, cell size (m).
  uTex: { value: null },
  uTexOn: { value: 0 },
  uGrid: { value: new THREE.Vector4(2, 2, 1, 1) },
};
const vertexShader = `
in vec2 morph;
uniform float uFrame;
uniform float uMorphFrames;
out vec3 vWorld;
out vec3 vNormal;
void main() {
  vNormal = normal;
  float k = clamp((uFrame - morph.y) / uMorphFrames, 0.0, 1.0);
  vec3 p = vec3(position.xy, mix(morph.x, position.z, k));
  vWorld = p;
  gl_Position = projectionMatrix * modelViewMatrix * vec4(p, 1.0);
}`;
const fragmentShader = `
layout(location = 0) out highp vec4 fragColor;
uniform vec3 uSun;
uniform vec2 uZRange;
uniform float uWire;
uniform float uFacets;
uniform sampler2D uTex;
uniform float uTexOn;
uniform vec4 uGrid;
in vec3 vWorld;
in vec3 vNormal;
void main() {
  if (uWire > 0.5) { fragColor = vec4(0.07, 0.09, 0.11, 1.0); return; }
  vec3 n = uFacets > 0.5 || dot(vNormal, vNormal) < 1e-6 ? normalize(cross(dFdx(vWorld), dFdy(vWorld))) : normalize(vNormal);
  if (n.z < 0.0) n = -n;
  float shade = clamp(dot(n, uSun), 0.0, 1.0);
  if (uTexOn > 0.5) {
    // The texture spans the samples: u = column / (W - 1), v = row / (H - 1), row 0 north.
    vec2 cr = vec2(vWorld.x / uGrid.z + 0.5 * (uGrid.x - 1.0), 0.5 * (uGrid.y - 1.0) - vWorld.y / uGrid.w);
    vec3 t = texture(uTex, cr / max(uGrid.xy - 1.0, vec2(1.0))).rgb;
    fragColor = vec4(min(t * (0.7 + 0.45 * shade), vec3(1.0)), 1.0);
    return;
  }
  if (vWorld.z <= 0.0) {
    float s = clamp(dot(normalize(vec3(0.0, 0.0, 1.0)), uSun), 0.0, 1.0);
    fragColor = vec4(vec3(0.16, 0.34, 0.52) * (0.6 + 0.4 * s), 1.0);
    return;
  }
  float h = clamp((vWorld.z - uZRange.x) / max(uZRange.y - uZRange.x, 1.0), 0.0, 1.0);
  vec3 low = vec3(0.30, 0.50, 0.28), mid = vec3(0.70, 0.63, 0.42), high = vec3(0.96, 0.95, 0.92);
  vec3 c = h < 0.5 ? mix(low, mid, h * 2.0) : mix(mid, high, h * 2.0 - 1.0);
  fragColor = vec4(c * (0.28 + 0.72 * shade), 1.0);
}`;
const fill = new THREE.ShaderMaterial({
  uniforms,
  vertexShader,
  fragmentShader,
  glslVersion: THREE.GLSL3,
  polygonOffset: true,
  polygonOffsetFactor: 1,
  polygonOffsetUnits: 1,
});
const wireUniforms = { ...uniforms, uWire: { value: 1 } };
const wire = new THREE.ShaderMaterial({ uniforms: wireUniforms, vertexShader, fragmentShader, glslVersion: THREE.GLSL3, wireframe: true });
let geometry = null;
let grownSeen = -1;
const fillMesh = new THREE.Mesh(new THREE.BufferGeometry(), fill);
const wireMesh = new THREE.Mesh(new THREE.BufferGeometry(), wire);
for (const m of [fillMesh, wireMesh]) {
  m.frustumCulled = false;
  scene.add(m);
}
wireMesh.visible = false;

let normals = null;

/** Per-vertex normal from the known heights around vertex v (central differences two cells wide). */
function vertexNormal(v) {
  const x = lod.position[3 * v], y = lod.position[3 * v + 1];
  const dx = 2 * meta.cell_size_m[0], dy = 2 * meta.cell_size_m[1];
  const gx = (groundZ(x + dx, y) - groundZ(x - dx, y)) / (2 * dx);
  const gy = (groundZ(x, y + dy) - groundZ(x, y - dy)) / (2 * dy);
  const l = Math.hypot(gx, gy, 1);
  normals[3 * v] = -gx / l;
  normals[3 * v + 1] = -gy / l;
  normals[3 * v + 2] = 1 / l;
}

/** (Re)wraps the LOD's arrays in a geometry (at start and when they grow). */
function rebuildGeometry() {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(lod.position, 3).setUsage(THREE.DynamicDrawUsage));
  g.setAttribute('morph', new THREE.BufferAttribute(lod.morph, 2).setUsage(THREE.DynamicDrawUsage));
  normals = new Float32Array(lod.position.length);
  for (let v = 0; v * 3 < normals.length; v++) vertexNormal(v);
  g.setAttribute('normal', new THREE.BufferAttribute(normals, 3).setUsage(THREE.DynamicDrawUsage));
  g.setIndex(new THREE.BufferAttribute(lod.index, 1).setUsage(THREE.DynamicDrawUsage));
  const r = Math.hypot(meta.width * meta.cell_size_m[0], meta.height * meta.cell_size_m[1]);
  g.boundingSphere = new THREE.Sphere(new THREE.Vector3(), r);
  if (geometry) geometry.dispose();
  geometry = g;
  fillMesh.geometry = g;
  wireMesh.geometry = g;
  grownSeen = lod.grown;
  lod.takeDirty();
}

/** Uploads only the pages of triangles and vertices that changed. */
function uploadChanges() {
  if (lod.grown !== grownSeen) {
    rebuildGeometry();
    return;
  }
  const { tri, vert } = lod.takeDirty();
  const page = 1024;
  for (const p of tri) geometry.index.addUpdateRange(p * page * 3, Math.min(page * 3, lod.index.length - p * page * 3));
  if (tri.length) geometry.index.needsUpdate = true;
  const pos = geometry.getAttribute('position');
  const mor = geometry.getAttribute('morph');
  const nor = geometry.getAttribute('normal');
  for (const p of vert) {
    const n3 = Math.min(page * 3, lod.position.length - p * page * 3);
    for (let v = p * page; v * 3 < p * page * 3 + n3; v++) vertexNormal(v);
    nor.addUpdateRange(p * page * 3, n3);
    pos.addUpdateRange(p * page * 3, n3);
    mor.addUpdateRange(p * page * 2, Math.min(page * 2, lod.morph.length - p * page * 2));
  }
  if (vert.length) {
    pos.needsUpdate = true;
    mor.needsUpdate = true;
    nor.needsUpdate = true;
  }
  geometry.setDrawRange(0, lod.triTop * 3);
}

// ---- navigation --------------------------------------------------------------

const orbit = new OrbitControls(camera, renderer.domElement);
orbit.listenToKeyEvents(window);
// Smooth damping; the polar angle stays above the horizon (85° from the zenith
// at most), and keepAboveGround() below holds the eye over the terrain.
orbit.enableDamping = true;
orbit.dampingFactor = 0.12;
orbit.maxPolarAngle = (85 * Math.PI) / 180;
const keys = new Set();
const look = { yaw: 0, pitch: 0, dragging: false, x: 0, y: 0 };
window.addEventListener('keydown', (e) => {
  keys.add(e.code);
  if (e.code === 'KeyT') nextColours();
  if (e.code === 'KeyF') toggleFly();
  if (e.code === 'KeyG') toggleWire();
  if (e.code === 'BracketLeft') setTarget(state.targetPx / 2);
  if (e.code === 'BracketRight') setTarget(state.targetPx * 2);
});
window.addEventListener('keyup', (e) => keys.delete(e.code));
renderer.domElement.addEventListener('pointerdown', (e) => {
  if (!state.fly) return;
  look.dragging = true;
  look.x = e.clientX;
  look.y = e.clientY;
});
window.addEventListener('pointerup', () => {
  look.dragging = false;
});
window.addEventListener('pointermove', (e) => {
  if (!state.fly || !look.dragging) return;
  look.yaw -= (e.clientX - look.x) * 0.004;
  look.pitch = Math.max(-1.5, Math.min(1.5, look.pitch - (e.clientY - look.y) * 0.004));
  look.x = e.clientX;
  look.y = e.clientY;
});
document.getElementById('mode').onclick = () => toggleFly();
document.getElementById('wire').onclick = () => toggleWire();
document.getElementById('colours').onclick = () => nextColours();
document.getElementById('finer').onclick = () => setTarget(state.targetPx / 2);
document.getElementById('coarser').onclick = () => setTarget(state.targetPx * 2);

function setTarget(px) {
  state.targetPx = Math.min(64, Math.max(0.25, px));
}

function toggleWire() {
  state.wire = !state.wire;
  wireMesh.visible = state.wire;
}

// ---- textures ------------------------------------------------------------------

const loaded = new Map();

/** The texture of `level` (meta.texture.image or .pair), loaded once. */
function loadTexture(level) {
  if (!loaded.has(level.url)) {
    loaded.set(level.url, new Promise((ok, no) => {
      new THREE.TextureLoader().load(level.url, (t) => {
        t.flipY = false; // row 0 of the PNG is the north row, v = 0
        t.colorSpace = THREE.NoColorSpace; // drawn as the image's own levels
        t.anisotropy = renderer.capabilities.getMaxAnisotropy();
        t.generateMipmaps = true;
        t.minFilter = THREE.LinearMipmapLinearFilter;
        t.needsUpdate = true;
        ok(t);
      }, undefined, () => no(new Error(`${level.url}: cannot load the texture`)));
    }));
  }
  return loaded.get(level.url);
}

/** Switches to the next colours: height, the image, the pair's texture level. */
function nextColours() {
  const all = ['height', ...state.textures];
  setColours(all[(all.indexOf(state.colours) + 1) % all.length]).catch((e) => fail(String(e.message || e)));
}

async function setColours(name) {
  const level = name === 'height' ? null : meta && meta.texture && meta.texture[name];
  if (name !== 'height' && !level) throw new Error(`no ${name} texture served`);
  state.colours = name;
  if (level) {
    const t = await loadTexture(level);
    if (state.colours !== name) return;
    uniforms.uTex.value = t;
  }
  uniforms.uTexOn.value = level ? 1 : 0;
  showColours();
}

/** The legend and the button say which colours are drawn. */
function showColours() {
  const name = state.colours;
  document.getElementById('colours').textContent = { height: 'heights', image: 'image', pair: 'pair' }[name];
  document.getElementById('legend-height').hidden = name !== 'height';
  const cap = document.getElementById('legend-texture');
  cap.hidden = name === 'height';
  const pair = document.getElementById('pair');
  pair.hidden = name !== 'pair';
  if (name === 'height') return;
  const a = meta.texture.image.about;
  const file = String(a.image || '').split(/[\\/]/).pop();
  const lv = meta.texture[name];
  cap.textContent = `colours: ${file}\nbands ${a.bands}, ${lv.width} × ${lv.height} texels\n${name === 'pair' ? 'the pair\'s texture level' : 'the whole image'} · T: next`;
  if (name === 'pair') {
    const p = lv.about;
    const n = (v) => Number(v).toLocaleString('en');
    pair.textContent = `paper 004's pair within ${n(p.budget_bytes)} bytes (${n(p.bytes)} used)\n`
      + `mesh     ${p.hierarchy} at ${p.tolerance_m} m: ${n(p.triangles)} triangles, ${n(p.mesh_bytes)} B\n`
      + `texture  tolerance ${p.texture_tolerance}: ${n(p.leaves)} flat leaves, ${n(p.texture_bytes)} B\n`
      + `chosen of ${p.meshes_listed} meshes × ${p.textures_listed} textures (the viewer's mesh\nstill follows the screen error; the pair's mesh is its figures)`;
  }
}

/** The warnings the server's input gave, in their panel (hidden when none). */
function showWarnings() {
  const w = meta.warnings || [];
  const el = document.getElementById('warnings');
  el.hidden = w.length === 0;
  if (!w.length) return;
  document.getElementById('warnings-head').textContent = `⚠ ${w.length} warning${w.length > 1 ? 's' : ''} about the input`;
  const ul = document.getElementById('warnings-list');
  ul.replaceChildren(...w.map((t) => {
    const li = document.createElement('li');
    li.textContent = t;
    return li;
  }));
}

function toggleFly() {
  state.fly = !state.fly;
  document.getElementById('mode').textContent = state.fly ? 'orbit' : 'fly';
  orbit.enabled = !state.fly;
  const d = new THREE.Vector3();
  camera.getWorldDirection(d);
  if (state.fly) {
    look.yaw = Math.atan2(d.y, d.x);
    look.pitch = Math.asin(Math.max(-1, Math.min(1, d.z)));
  } else {
    const dist = Math.max(100, camera.position.z - groundZ(camera.position.x, camera.position.y));
    orbit.target.copy(camera.position).addScaledVector(d, dist * 2);
    orbit.update();
  }
}

/** Height of the nearest sample known so far under local (x, y). */
function groundZ(x, y) {
  if (!meta) return 0;
  const w = meta.width, h = meta.height;
  const col = Math.round(x / meta.cell_size_m[0] + (w - 1) / 2);
  const row = Math.round((h - 1) / 2 - y / meta.cell_size_m[1]);
  if (col < 0 || row < 0 || col >= w || row >= h) return meta.height_range_m[0];
  for (let s = 1; s <= 1 << 16; s *= 2) {
    const c = Math.round(col / s) * s, r = Math.round(row / s) * s;
    if (c < w && r < h && stepOf[r * w + c] !== 255) return heights[r * w + c];
  }
  return meta.height_range_m[0];
}

function flyStep(dt) {
  const dir = new THREE.Vector3(Math.cos(look.pitch) * Math.cos(look.yaw), Math.cos(look.pitch) * Math.sin(look.yaw), Math.sin(look.pitch));
  const right = new THREE.Vector3(Math.sin(look.yaw), -Math.cos(look.yaw), 0);
  const agl = Math.max(30, camera.position.z - groundZ(camera.position.x, camera.position.y));
  const speed = agl * (keys.has('ShiftLeft') || keys.has('ShiftRight') ? 5 : 1) * dt;
  const p = camera.position;
  if (keys.has('KeyW') || keys.has('ArrowUp')) p.addScaledVector(dir, speed);
  if (keys.has('KeyS') || keys.has('ArrowDown')) p.addScaledVector(dir, -speed);
  if (keys.has('KeyD') || keys.has('ArrowRight')) p.addScaledVector(right, speed);
  if (keys.has('KeyA') || keys.has('ArrowLeft')) p.addScaledVector(right, -speed);
  if (keys.has('KeyE')) p.z += speed;
  if (keys.has('KeyQ')) p.z -= speed;
  camera.lookAt(p.clone().add(dir));
}

/** Lifts the eye to at least a margin above the ground under it (orbit and fly). */
function keepAboveGround() {
  const p = camera.position;
  const g = groundZ(p.x, p.y);
  const margin = Math.max(10, 2 * Math.max(meta.cell_size_m[0], meta.cell_size_m[1]));
  if (p.z < g + margin) p.z = g + margin;
}

/** The default view: the whole extent in the frame, from the south, looking down at about 30°. */
function homeView() {
  state.scripted = false;
  if (state.fly) toggleFly();
  orbit.enabled = true;
  const ext = Math.max(meta.width * meta.cell_size_m[0], meta.height * meta.cell_size_m[1]);
  camera.position.set(-0.1 * ext, -0.75 * ext, 0.45 * ext);
  orbit.target.set(0, 0, meta.height_range_m[0]);
  orbit.update();
}

// ---- map furniture -------------------------------------------------------------

const furniture = { mouse: null, moved: false };
renderer.domElement.addEventListener('pointermove', (e) => {
  furniture.mouse = [e.clientX, e.clientY];
  furniture.moved = true;
});

/** A longitude within ±180° (a grid laid out across the antimeridian runs past 180°). */
const wrapLon = (lon) => (lon > 180 ? lon - 360 : lon < -180 ? lon + 360 : lon);

/** Longitude/latitude of local (x, y), or null for a grid without them. */
function lonLat(x, y) {
  const b = meta.lon_lat_bounds;
  if (!b) return null;
  const col = x / meta.cell_size_m[0] + (meta.width - 1) / 2;
  const row = (meta.height - 1) / 2 - y / meta.cell_size_m[1];
  return [wrapLon(b[0] + (col / (meta.width - 1)) * (b[2] - b[0])), b[1] + (row / (meta.height - 1)) * (b[3] - b[1])];
}

/** Where the ray through screen pixel (sx, sy) first meets the ground, marching along it. */
function groundAt(sx, sy) {
  const el = renderer.domElement;
  const ndc = new THREE.Vector3((sx / el.clientWidth) * 2 - 1, -(sy / el.clientHeight) * 2 + 1, 0.5);
  const dir = ndc.unproject(camera).sub(camera.position).normalize();
  const p = camera.position.clone();
  let step = Math.max(1, (p.z - groundZ(p.x, p.y)) * 0.02);
  const far = 4 * Math.hypot(meta.width * meta.cell_size_m[0], meta.height * meta.cell_size_m[1]);
  let prev = p.clone();
  for (let t = 0; t < far; t += step, step *= 1.03) {
    const q = camera.position.clone().addScaledVector(dir, t);
    if (q.z <= groundZ(q.x, q.y)) {
      // Halve back between prev and q a few times.
      let a = prev, b = q;
      for (let k = 0; k < 12; k++) {
        const m = a.clone().lerp(b, 0.5);
        if (m.z <= groundZ(m.x, m.y)) b = m;
        else a = m;
      }
      return b;
    }
    prev = q;
  }
  return null;
}

function niceLength(m) {
  const e = 10 ** Math.floor(Math.log10(m));
  for (const k of [5, 2, 1]) if (k * e <= m) return k * e;
  return e;
}

const deg = (v, pos, neg, d) => `${Math.abs(v).toFixed(d)}° ${v < 0 ? neg : pos}`;
const fmtLen = (m) => (m >= 1000 ? `${m / 1000} km` : `${m} m`);

function setupFurniture() {
  const [lo, hi] = meta.height_range_m;
  const stops = ['rgb(77,128,71) 0%', 'rgb(179,161,107) 50%', 'rgb(245,242,235) 100%'];
  let grad = stops.join(', ');
  if (lo < 0 && hi > 0) {
    const w = (100 * -lo) / (hi - lo);
    grad = `rgb(41,87,133) 0%, rgb(41,87,133) ${w.toFixed(1)}%, rgb(77,128,71) ${w.toFixed(1)}%, rgb(179,161,107) 50%, rgb(245,242,235) 100%`;
  }
  document.getElementById('legend-bar').style.background = `linear-gradient(to right, ${grad})`;
  const ticks = [lo, (lo + hi) / 2, hi].map((v) => `<span>${Math.round(v)}</span>`).join('');
  document.getElementById('legend-ticks').innerHTML = ticks;
  const wkm = (meta.width * meta.cell_size_m[0]) / 1000, hkm = (meta.height * meta.cell_size_m[1]) / 1000;
  const b = meta.lon_lat_bounds;
  const ext = b ? `\n${deg(wrapLon(b[0]), 'E', 'W', 3)} … ${deg(wrapLon(b[2]), 'E', 'W', 3)}, ${deg(b[3], 'N', 'S', 3)} … ${deg(b[1], 'N', 'S', 3)}` : '';
  const names = meta.name.split(' + ').map((f) => f.split(/[\\/]/).pop()).join(' + ');
  document.getElementById('dataset').textContent =
    `${names}\n${meta.width} × ${meta.height} samples, ${wkm.toFixed(1)} × ${hkm.toFixed(1)} km, ${Math.round(lo)}…${Math.round(hi)} m${ext}`;
}

function updateFurniture() {
  const d = new THREE.Vector3();
  camera.getWorldDirection(d);
  const heading = Math.atan2(d.x, d.y); // 0 looking north
  document.getElementById('needle').setAttribute('transform', `rotate(${((-heading * 180) / Math.PI).toFixed(1)})`);
  const el = renderer.domElement;
  const hit = groundAt(el.clientWidth / 2, el.clientHeight / 2);
  const dist = hit ? hit.distanceTo(camera.position) : Math.max(1, camera.position.z - groundZ(camera.position.x, camera.position.y));
  const mPerPx = (dist * 2 * Math.tan((camera.fov * Math.PI) / 360)) / el.clientHeight;
  const len = niceLength(mPerPx * 180);
  document.getElementById('scale-bar').style.width = `${Math.round(len / mPerPx)}px`;
  document.getElementById('scale-label').textContent = `${fmtLen(len)} (at the view's centre)`;
  if (furniture.moved && furniture.mouse) {
    furniture.moved = false;
    const g = groundAt(furniture.mouse[0], furniture.mouse[1]);
    const c = document.getElementById('cursor');
    if (!g) c.textContent = 'cursor: off the terrain';
    else {
      const ll = lonLat(g.x, g.y);
      c.textContent = `cursor: ${ll ? `${deg(ll[1], 'N', 'S', 5)}  ${deg(ll[0], 'E', 'W', 5)}` : `x ${g.x.toFixed(0)} m  y ${g.y.toFixed(0)} m`}  height ${groundZ(g.x, g.y).toFixed(0)} m`;
    }
  }
}

function setView(eye, target) {
  state.scripted = true;
  orbit.enabled = false;
  camera.position.set(eye[0], eye[1], eye[2]);
  camera.lookAt(target[0], target[1], target[2]);
}

// ---- the stream --------------------------------------------------------------

function onStep(m) {
  for (let k = 0; k < m.points.length; k++) {
    heights[m.points[k]] = m.heights[k];
    stepOf[m.points[k]] = m.index;
  }
  lod.addStep(m.index, m.maxErrorM, m.points);
  state.steps = m.index + 1;
  state.received = m.received;
  state.lastEndOffset = m.endOffset;
  state.decodeMs = m.decodeMs;
  if (m.index === 0) rebuildGeometry();
}

function startWorker() {
  const worker = new Worker(__COTA_WORKER__);
  worker.onmessage = (e) => {
    const m = e.data;
    if (m.type === 'head') {
      state.total = m.total;
      state.stepsAnnounced = m.steps;
    } else if (m.type === 'step') {
      onStep(m);
    } else if (m.type === 'done') {
      state.done = true;
      state.received = m.received;
    } else if (m.type === 'error') {
      fail(`stream: ${m.message}`);
    }
  };
  worker.onerror = (e) => fail(`worker: ${e.message}`);
  worker.postMessage({ type: 'start', url: '/stream' });
}

// ---- frames ------------------------------------------------------------------

function median(a) {
  if (!a.length) return 0;
  const s = [...a].sort((x, y) => x - y);
  return s[s.length >> 1];
}

function stats() {
  return {
    frame: frameNo,
    triangles: lod ? lod.triCount : 0,
    refineMs: state.refineMs.at(-1) ?? 0,
    refineMedianMs: median(state.refineMs.slice(-120)),
    bytes: state.received,
    total: state.total,
    steps: state.steps,
    stepsAnnounced: state.stepsAnnounced,
    done: state.done,
    targetPx: state.targetPx,
    maxError: state.maxError,
    firstDraw: state.firstDraw,
    pending: lod ? lod.pending : false,
    eye: camera.position.toArray(),
  };
}

function drawOverlay() {
  const s = stats();
  const kb = (b) => `${(b / 1024).toFixed(0)} KB`;
  overlay.textContent = [
    `triangles   ${s.triangles.toLocaleString('en')}`,
    `refine      ${s.refineMs.toFixed(2)} ms/frame (median ${s.refineMedianMs.toFixed(2)})`,
    `stream      ${kb(s.bytes)} of ${kb(s.total)}, step ${s.steps}/${s.stepsAnnounced}${s.done ? ' (done)' : ''}`,
    `screen err  max ${s.maxError.sent.toFixed(2)} px, target ${s.targetPx} px`,
    `            (how far, in pixels, the drawn surface\n             may be from the full data${s.maxError.all > s.maxError.sent + 1e-9 ? `;\n             ${s.maxError.all.toFixed(1)} px until the rest arrives` : ''})`,
    `mode        ${state.fly ? 'fly' : 'orbit'}${state.wire ? ', wireframe' : ''}`,
  ].join('\n');
}

let last = performance.now();
function frame(now) {
  requestAnimationFrame(frame);
  const dt = Math.min(0.1, (now - last) / 1000);
  last = now;
  if (!lod || !geometry) return;
  if (!state.scripted) {
    if (state.fly) flyStep(dt);
    else orbit.update();
    keepAboveGround();
    const p = camera.position;
    state.minClearance = Math.min(state.minClearance, p.z - groundZ(p.x, p.y));
  }
  const agl = camera.position.z - groundZ(camera.position.x, camera.position.y);
  camera.near = Math.min(2000, Math.max(1, agl * 0.25));
  camera.far = Math.max(1e5, 8 * Math.hypot(meta.width * meta.cell_size_m[0], camera.position.z));
  camera.updateProjectionMatrix();
  const K = renderer.domElement.clientHeight / (2 * Math.tan((camera.fov * Math.PI) / 360));
  const t = performance.now();
  lod.update(camera.position.toArray(), K, state.targetPx, state.budgetMs);
  const ms = performance.now() - t;
  state.refineMs.push(ms);
  state.triangles.push(lod.triCount);
  if (state.refineMs.length > 100000) state.refineMs.splice(0, 50000);
  uploadChanges();
  if (frameNo % 4 === 0) updateFurniture();
  uniforms.uFrame.value = lod.frame;
  wireUniforms.uFrame.value = lod.frame;
  renderer.render(scene, camera);
  frameNo++;
  if (!state.firstDraw && lod.triCount > 0) {
    state.firstDraw = { bytesReceived: state.received, streamOffset: state.lastEndOffset, ms: performance.now() - state.t0, triangles: lod.triCount };
  }
  if (frameNo % 30 === 1) state.maxError = lod.maxScreenError();
  drawOverlay();
  for (let k = waiters.length - 1; k >= 0; k--) {
    if (frameNo >= waiters[k].frame) {
      waiters[k].resolve(stats());
      waiters.splice(k, 1);
    }
  }
}

/** Renders now and reads the frame back (for tests): its RGBA pixels, size, and the sky's colour. */
function readFrame() {
  renderer.render(scene, camera);
  const gl = renderer.getContext();
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  const px = new Uint8Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  // The clear colour as drawn: sRGB (Color's r, g, b are linear).
  const sky = scene.background.getHex();
  const sr = (sky >> 16) & 255, sg = (sky >> 8) & 255, sb = sky & 255;
  return { px, w, h, sr, sg, sb };
}

/** Renders now and measures the mean squared luminance step between neighbouring terrain pixels (for tests). */
function roughness() {
  const { px, w, h, sr, sg, sb } = readFrame();
  const lum = (i) => 0.2126 * px[i] + 0.7152 * px[i + 1] + 0.0722 * px[i + 2];
  const isSky = (i) => Math.abs(px[i] - sr) + Math.abs(px[i + 1] - sg) + Math.abs(px[i + 2] - sb) <= 12;
  let sum = 0, n = 0;
  for (let y = 0; y + 1 < h; y++) {
    for (let x = 0; x + 1 < w; x++) {
      const i = 4 * (y * w + x), r = i + 4, d = i + 4 * w;
      if (isSky(i) || isSky(r) || isSky(d)) continue;
      const a = lum(i);
      sum += (lum(r) - a) ** 2 + (lum(d) - a) ** 2;
      n += 2;
    }
  }
  return { meanSquaredStep: n ? sum / n : 0, pairs: n };
}

function pixels() {
  const { px, w, h, sr, sg, sb } = readFrame();
  let terrain = 0;
  const shades = new Set();
  for (let i = 0; i < px.length; i += 4) {
    if (Math.abs(px[i] - sr) + Math.abs(px[i + 1] - sg) + Math.abs(px[i + 2] - sb) > 12) {
      terrain++;
      shades.add((px[i] >> 3) * 1024 + (px[i + 1] >> 3) * 32 + (px[i + 2] >> 3));
    }
  }
  return { width: w, height: h, terrainFraction: terrain / (w * h), shades: shades.size };
}

function colourGrid(n) {
  const { px, w, h, sr, sg, sb } = readFrame();
  const terrain = (i) => Math.abs(px[i] - sr) + Math.abs(px[i + 1] - sg) + Math.abs(px[i + 2] - sb) > 12;
  let [x0, x1, y0, y1] = [w, -1, h, -1];
  const mean = [0, 0, 0];
  let count = 0;
  for (let y = 0; y < h; y++) {
    for (let x = 0; x < w; x++) {
      const i = 4 * (y * w + x);
      if (!terrain(i)) continue;
      count++;
      for (let k = 0; k < 3; k++) mean[k] += px[i + k];
      x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y);
    }
  }
  const cells = Array.from({ length: n * n }, () => [0, 0, 0, 0]);
  for (let y = y0; y <= y1; y++) {
    for (let x = x0; x <= x1; x++) {
      const i = 4 * (y * w + x);
      if (!terrain(i)) continue;
      // readPixels' row 0 is the bottom of the screen.
      const cx = Math.min(n - 1, Math.floor(((x - x0) / (x1 - x0 + 1)) * n));
      const cy = Math.min(n - 1, Math.floor(((y1 - y) / (y1 - y0 + 1)) * n));
      const c = cells[cy * n + cx];
      for (let k = 0; k < 3; k++) c[k] += px[i + k];
      c[3]++;
    }
  }
  return {
    mean: mean.map((v) => v / Math.max(1, count)),
    terrainPixels: count,
    box: [x0, h - 1 - y1, x1, h - 1 - y0],
    grid: cells.map((c) => (c[3] ? [c[0] / c[3], c[1] / c[3], c[2] / c[3]] : null)),
  };
}

window.addEventListener('resize', () => {
  renderer.setSize(window.innerWidth, window.innerHeight);
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
});

/** fetch(url), waiting out 503 answers (the server still encoding the stream) as Retry-After says. */
async function fetchReady(url, onWait) {
  for (;;) {
    const r = await fetch(url);
    if (r.status !== 503) return r;
    const s = Number(r.headers.get('Retry-After')) || 1;
    if (onWait) onWait(s);
    await new Promise((ok) => setTimeout(ok, 1000 * Math.min(s, 10)));
  }
}

async function main() {
  const r = await fetchReady('/meta.json', () => { overlay.textContent = 'the server is encoding the stream…'; });
  if (!r.ok) throw new Error(`/meta.json: HTTP ${r.status}`);
  meta = await r.json();
  const n = meta.width * meta.height;
  heights = new Float32Array(n);
  stepOf = new Uint8Array(n).fill(255);
  lod = new Lod({ width: meta.width, height: meta.height, cellX: meta.cell_size_m[0], cellY: meta.cell_size_m[1], heights, stepOf });
  uniforms.uZRange.value.set(meta.height_range_m[0], meta.height_range_m[1]);
  uniforms.uGrid.value.set(meta.width, meta.height, meta.cell_size_m[0], meta.cell_size_m[1]);
  homeView();
  setupFurniture();
  showWarnings();
  state.textures = ['image', 'pair'].filter((k) => meta.texture && meta.texture[k]);
  document.getElementById('colours').hidden = !state.textures.length;
  document.getElementById('help-texture').hidden = !state.textures.length;
  if (state.textures.length) setColours('image').catch((e) => fail(String(e.message || e)));
  startWorker();
  api.ready = true;
  requestAnimationFrame(frame);
}

main().catch((e) => fail(String(e.message || e)));
