// View-dependent remeshing of the bitree, incremental from frame to frame.
//
// Paper 001 (../../../../shared/seeds/001_49f2c365e8c41172.txt, "Remallado de
// terrenos multirresolución"): the frontier of the binary tree of right
// triangles is the mesh shown; where the observer comes closer triangles split,
// where it has left they merge back upward from the leaves. Paper 000
// (000_ebf7e3a88dffd361.txt) gives the hierarchy and its dependencies: a split
// point needs the two apexes of its diamond (ROAM's forced splits), so the
// mesh is always conforming (no T-junction, no crack).
//
// The criterion is the screen-space error in pixels of each diamond:
//   e(m) = bound(m) · K / d(m),  K = viewport height / (2 tan(fov / 2)),
// with d(m) the distance from the eye to a sphere around the diamond and
// bound(m) cota's error bound for the diamond, carried by the progressive
// stream: a split point first split in step k had its exact error at most the
// stated error of step k − 1 (every split point left unsplit by a step has its
// error at most that step's stated error), so leaving it unsplit costs at most
// that bound at every grid sample of its diamond.
//
// Incremental: each candidate (a split point that could split now, or one that
// could merge now) is evaluated once and scheduled again for the moment the
// eye has travelled far enough to change the decision (its slack in metres:
// the distance can change by no more than the eye moved). Each frame takes out
// only the candidates whose slack is used up, so the work per frame follows
// the change of the mesh, not its size; nothing is rebuilt. The schedule
// (queue.js) keeps with each entry its diamond's sphere and target distance,
// so deciding again a candidate whose slack ran out is a distance and a
// compare, without reading the grid; a candidate enters the schedule only
// when its state changes (a split makes the child points it uncovered
// candidates, a merge makes its apexes candidates again once they have no
// split child, and takes out the child points it covered), never to find that
// nothing can be decided.
//
// Geomorphing: a new vertex starts at the midpoint of its hypotenuse (where the
// coarser surface had it: the fictitious point of paper 000) and moves to its
// real height over `morphFrames` frames (on the GPU, from a start height and a
// start frame per vertex).

import { SlackQueue } from './queue.js';

const SQRT2 = Math.SQRT2;
/**
 * Splits happen above this fraction of the target, so that a diamond left
 * unsplit has a slack of at least (1 / SPLIT_FRACTION − 1) of its critical
 * distance before it can reach the target: fewer re-evaluations.
 */
const SPLIT_FRACTION = 1;
/** Merges happen below this fraction of the target (hysteresis). */
const MERGE_FRACTION = 0.8;
/**
 * Refinement time allowed per frame, in milliseconds: what is left waits for
 * the next frame (issue 32: p90 ≤ 4 ms per frame while the error converges).
 */
export const FRAME_BUDGET_MS = 4;
/** Candidates evaluated between two looks at the clock. */
const CLOCK_EVERY = 32;
/** Schedule entries passed over (not due yet) between two looks at the clock. */
const SCAN_EVERY = 1024;

/** Edge index (0..3) of the direction (dx, dy) from an apex to a child point. */
function edgeIndex(dx, dy) {
  if (dx === 0) return dy < 0 ? 0 : 2;
  if (dy === 0) return dx > 0 ? 1 : 3;
  if (dy < 0) return dx > 0 ? 0 : 3;
  return dx > 0 ? 1 : 2;
}

export class Lod {
  /**
   * @param {object} o width, height (samples), cellX, cellY (metres),
   *   heights (Float32Array, filled as steps arrive), stepOf (Uint8Array, 255
   *   for points not split yet), morphFrames.
   */
  constructor(o) {
    this.w = o.width;
    this.h = o.height;
    const span = Math.max(Math.max(this.w, this.h) - 1, 1);
    let n = 1;
    while (n < span) n *= 2;
    this.N = n;
    this.cellX = o.cellX;
    this.cellY = o.cellY;
    this.cell = Math.max(o.cellX, o.cellY);
    this.z = o.heights;
    this.stepOf = o.stepOf;
    this.morphFrames = o.morphFrames ?? 8;
    const len = this.w * this.h;
    this.active = new Uint8Array(len); // 0 no, 1 split, 2 split in step 0 (never merges)
    this.bounds = new Float64Array(256).fill(Infinity);
    this.stated = [];
    this.queue = new SlackQueue(len);
    this.travel = 0;
    this.eye = null;
    this.K = 1;
    this.targetPx = 1;
    this.frame = 0;
    this.triSlot = new Int32Array(len * 4 + 2).fill(-1);
    this.triCount = 0;
    this.initTriangles(1 << 14);
    this.initVertices(1 << 13, len);
    this.rootsInside = this.N + 1 <= this.w && this.N + 1 <= this.h;
    this.rootMid = (this.N / 2) * this.w + this.N / 2;
    this.scratch = new Int32Array(8);
    this.scratch2 = new Int32Array(8);
    this.scratch3 = new Int32Array(8);
    this.scratch4 = new Int32Array(8);
    this.scratch5 = new Int32Array(8);
    this.splits = 0;
    this.merges = 0;
    this.evaluations = 0;
    /** Evaluations that read the grid (the others read their queue entry alone). */
    this.fullEvaluations = 0;
  }

  initTriangles(cap) {
    this.triCap = cap;
    this.index = new Uint32Array(cap * 3);
    this.triSamples = new Int32Array(cap * 3);
    this.triKey = new Int32Array(cap).fill(-1);
    this.triFree = [];
    this.triTop = 0;
    this.triDirty = [];
    this.triPageDirty = new Uint8Array((cap >> 10) + 1);
  }

  initVertices(cap, len) {
    this.vertCap = cap;
    this.position = new Float32Array(cap * 3);
    this.morph = new Float32Array(cap * 2);
    this.vertFree = [];
    this.vertTop = 0;
    this.vertDirty = [];
    this.vertPageDirty = new Uint8Array((cap >> 10) + 1);
    this.slotOf = new Int32Array(len).fill(-1);
    this.refs = new Uint8Array(len);
    this.grown = 0;
  }

  // ---- geometry of the implicit hierarchy --------------------------------

  isCorner(x, y) {
    return (x === 0 || x === this.N) && (y === 0 || y === this.N);
  }

  inGrid(x, y) {
    return x >= 0 && y >= 0 && x < this.w && y < this.h;
  }

  /**
   * Diamond of split point (x, y) into `s`: s[0..7] = V0..V3 (x, y pairs, in
   * cyclic order), returns t | (A-type ? 1 << 30 : 0) | (apexes V1, V3 ? 1 << 29 : 0).
   */
  diamond(x, y, s) {
    const or = x | y;
    const t = or & -or;
    const oddX = (x & t) !== 0, oddY = (y & t) !== 0;
    let flags;
    if (oddX && oddY) {
      s[0] = x - t; s[1] = y - t; s[2] = x + t; s[3] = y - t;
      s[4] = x + t; s[5] = y + t; s[6] = x - t; s[7] = y + t;
      const i = (x - t) / (2 * t), j = (y - t) / (2 * t);
      flags = (1 << 30) | (((i + j) & 1) === 0 ? 1 << 29 : 0);
    } else {
      s[0] = x; s[1] = y - t; s[2] = x + t; s[3] = y;
      s[4] = x; s[5] = y + t; s[6] = x - t; s[7] = y;
      flags = oddX ? 0 : 1 << 29;
    }
    return flags | t;
  }

  // ---- the stream ---------------------------------------------------------

  /** Applies a decoded step: `points` were split in it (heights already set). */
  addStep(index, statedM, points) {
    this.stated[index] = statedM;
    if (index > 0) this.bounds[index] = this.stated[index - 1];
    if (index === 0) {
      for (const i of points) this.active[i] = 2;
      this.buildBase();
      return;
    }
    for (const i of points) {
      if (this.isCandidate(i)) this.queue.push(i, this.travel, 0, 0, 0, 0);
    }
  }

  /** Stated error of the latest step (the bound of points not sent yet). */
  latestStated() {
    return this.stated.length ? this.stated[this.stated.length - 1] : Infinity;
  }

  buildBase() {
    const { w, h, active } = this;
    for (let i = 0; i < w * h; i++) {
      if (active[i]) this.addChildLeaves(i, false);
    }
    if (this.rootsInside && !active[this.rootMid]) this.addRoots();
    for (let i = 0; i < w * h; i++) {
      if (this.isCandidate(i)) this.queue.push(i, this.travel, 0, 0, 0, 0);
    }
  }

  addRoots() {
    const N = this.N;
    this.addTri(this.w * this.h * 4, N, 0, 0, 0, N, N, -1);
    this.addTri(this.w * this.h * 4 + 1, 0, N, N, N, 0, 0, -1);
  }

  /** Adds the child triangles of active point i whose split point is not active. */
  addChildLeaves(i, morphing) {
    const x = i % this.w, y = (i / this.w) | 0;
    const s = this.scratch;
    const f = this.diamond(x, y, s);
    const t = f & 0xffffff;
    const unitChildren = (f & (1 << 30)) === 0 && t === 1;
    for (let k = 0; k < 4; k++) {
      const px = s[2 * k], py = s[2 * k + 1];
      const qx = s[(2 * k + 2) & 7], qy = s[(2 * k + 3) & 7];
      if (!this.inGrid(px, py) || !this.inGrid(qx, qy)) continue;
      if (!unitChildren) {
        const c = ((py + qy) >> 1) * this.w + ((px + qx) >> 1);
        if (this.active[c]) continue;
      }
      this.addTri(i * 4 + k, x, y, px, py, qx, qy, morphing ? i : -1);
    }
  }

  /** True when i could split now: sent, not split, one of its triangles in the mesh. */
  isCandidate(i) {
    if (this.active[i] || this.stepOf[i] === 255) return false;
    const x = i % this.w, y = (i / this.w) | 0;
    if (this.isCorner(x, y)) return false;
    if (i === this.rootMid && this.rootsInside) return true;
    const s = this.scratch;
    const f = this.diamond(x, y, s);
    const o = f & (1 << 29) ? 2 : 0;
    return this.present(s[o], s[o + 1]) || this.present(s[o + 4], s[o + 5]);
  }

  /** True when (x, y) is a split point of the mesh. */
  present(x, y) {
    return x >= 0 && y >= 0 && x < this.w && y < this.h && this.active[y * this.w + x] !== 0;
  }

  // ---- triangles and vertices --------------------------------------------

  /** Adds leaf `key` = (c, p, q); `fresh` is the new vertex to morph (or −1). */
  addTri(key, cx, cy, px, py, qx, qy, fresh) {
    let slot = this.triFree.pop();
    if (slot === undefined) {
      if (this.triTop === this.triCap) this.growTriangles();
      slot = this.triTop++;
    }
    // Counter-clockwise seen from above in the east/north frame (y = −row).
    const o = (px - cx) * (cy - qy) - (cy - py) * (qx - cx);
    if (o < 0) {
      const tx = px, ty = py;
      px = qx; py = qy; qx = tx; qy = ty;
    }
    const w = this.w;
    const i0 = cy * w + cx, i1 = py * w + px, i2 = qy * w + qx;
    const b = slot * 3;
    this.triSamples[b] = i0;
    this.triSamples[b + 1] = i1;
    this.triSamples[b + 2] = i2;
    this.index[b] = this.useVertex(i0, i0 === fresh);
    this.index[b + 1] = this.useVertex(i1, i1 === fresh);
    this.index[b + 2] = this.useVertex(i2, i2 === fresh);
    this.triSlot[key] = slot;
    this.triKey[slot] = key;
    this.triCount++;
    this.markTri(slot);
  }

  removeTri(key) {
    const slot = this.triSlot[key];
    if (slot < 0) return;
    this.triSlot[key] = -1;
    this.triKey[slot] = -1;
    this.triCount--;
    for (let v = 0; v < 3; v++) this.releaseVertex(this.triSamples[slot * 3 + v]);
    this.index[slot * 3] = this.index[slot * 3 + 1] = this.index[slot * 3 + 2] = 0;
    this.triFree.push(slot);
    this.markTri(slot);
  }

  markTri(slot) {
    const page = slot >> 10;
    if (!this.triPageDirty[page]) {
      this.triPageDirty[page] = 1;
      this.triDirty.push(page);
    }
  }

  /** The dirty pages (1024 triangles or vertices each) since the last call. */
  takeDirty() {
    const out = { tri: this.triDirty, vert: this.vertDirty };
    for (const p of out.tri) this.triPageDirty[p] = 0;
    for (const p of out.vert) this.vertPageDirty[p] = 0;
    this.triDirty = [];
    this.vertDirty = [];
    return out;
  }

  growTriangles() {
    const cap = this.triCap * 2;
    const index = new Uint32Array(cap * 3);
    index.set(this.index);
    const samples = new Int32Array(cap * 3);
    samples.set(this.triSamples);
    const keys = new Int32Array(cap).fill(-1);
    keys.set(this.triKey);
    this.triKey = keys;
    this.index = index;
    this.triSamples = samples;
    this.triCap = cap;
    const d = new Uint8Array((cap >> 10) + 1);
    d.set(this.triPageDirty);
    this.triPageDirty = d;
    this.grown++;
  }

  /** The vertex slot of sample i, allocated on its first use. */
  useVertex(i, fresh) {
    if (this.refs[i]++ > 0) return this.slotOf[i];
    let slot = this.vertFree.pop();
    if (slot === undefined) {
      if (this.vertTop === this.vertCap) this.growVertices();
      slot = this.vertTop++;
    }
    this.slotOf[i] = slot;
    const x = i % this.w, y = (i / this.w) | 0;
    const p = this.position, m = this.morph;
    p[slot * 3] = (x - (this.w - 1) / 2) * this.cellX;
    p[slot * 3 + 1] = ((this.h - 1) / 2 - y) * this.cellY;
    p[slot * 3 + 2] = this.z[i];
    if (fresh) {
      m[slot * 2] = this.morphStart(i);
      m[slot * 2 + 1] = this.frame;
    } else {
      m[slot * 2] = this.z[i];
      m[slot * 2 + 1] = -1e9;
    }
    const page = slot >> 10;
    if (!this.vertPageDirty[page]) {
      this.vertPageDirty[page] = 1;
      this.vertDirty.push(page);
    }
    return slot;
  }

  releaseVertex(i) {
    if (--this.refs[i] > 0) return;
    this.vertFree.push(this.slotOf[i]);
    this.slotOf[i] = -1;
  }

  growVertices() {
    const cap = this.vertCap * 2;
    const p = new Float32Array(cap * 3);
    p.set(this.position);
    const m = new Float32Array(cap * 2);
    m.set(this.morph);
    this.position = p;
    this.morph = m;
    this.vertCap = cap;
    const d = new Uint8Array((cap >> 10) + 1);
    d.set(this.vertPageDirty);
    this.vertPageDirty = d;
    this.grown++;
  }

  /** Height shown now at sample i (morphing or not); i must be in the mesh. */
  shownZ(i) {
    const s = this.slotOf[i];
    if (s < 0) return this.z[i];
    const k = Math.min(Math.max((this.frame - this.morph[s * 2 + 1]) / this.morphFrames, 0), 1);
    return this.morph[s * 2] + (this.z[i] - this.morph[s * 2]) * k;
  }

  /** Where a new vertex starts: the midpoint of its hypotenuse as shown now. */
  morphStart(i) {
    const x = i % this.w, y = (i / this.w) | 0;
    const s = this.scratch3;
    const f = this.diamond(x, y, s);
    const o = f & (1 << 29) ? 0 : 2; // the ends are the pair that is not the apexes
    const a = s[o + 1] * this.w + s[o], b = s[o + 5] * this.w + s[o + 4];
    return (this.shownZ(a) + this.shownZ(b)) / 2;
  }

  // ---- split and merge ----------------------------------------------------

  /**
   * Splits i, first forcing its apexes (ROAM's forced splits). The caller
   * schedules i as a merge candidate (a forced apex has a split child at once).
   */
  split(i) {
    if (this.active[i]) return;
    const w = this.w;
    const x = i % w, y = (i / w) | 0;
    const s = this.scratch;
    const f = this.diamond(x, y, s);
    const o = f & (1 << 29) ? 2 : 0;
    const c1x = s[o], c1y = s[o + 1], c2x = s[o + 4], c2y = s[o + 5];
    const use1 = this.inGrid(c1x, c1y) && !this.isCorner(c1x, c1y);
    const use2 = this.inGrid(c2x, c2y) && !this.isCorner(c2x, c2y);
    if (use1 && !this.active[c1y * w + c1x]) this.split(c1y * w + c1x);
    if (use2 && !this.active[c2y * w + c2x]) this.split(c2y * w + c2x);
    this.active[i] = 1;
    this.splits++;
    this.addChildLeaves(i, true);
    if (use1) this.removeTri((c1y * w + c1x) * 4 + edgeIndex(x - c1x, y - c1y));
    if (use2) this.removeTri((c2y * w + c2x) * 4 + edgeIndex(x - c2x, y - c2y));
    if (i === this.rootMid && this.rootsInside) {
      this.removeTri(w * this.h * 4);
      this.removeTri(w * this.h * 4 + 1);
    }
    // i is no longer a split candidate; its apexes now have a split child, so
    // they cannot merge until it merges back (merge schedules them then).
    const q = this.queue;
    q.remove(i);
    if (use1 && this.active[c1y * w + c1x] === 1) q.remove(c1y * w + c1x);
    if (use2 && this.active[c2y * w + c2x] === 1) q.remove(c2y * w + c2x);
    this.scheduleChildren(i);
  }

  /**
   * Schedules the child points of i (just split) that it made candidates,
   * with their decision's constants (those that were candidates already, by
   * their other apex, keep their entry).
   */
  scheduleChildren(i) {
    const w = this.w;
    const x = i % w, y = (i / w) | 0;
    const s = this.scratch2, g = this.scratch5;
    const f = this.diamond(x, y, s);
    if ((f & (1 << 30)) === 0 && (f & 0xffffff) === 1) return;
    const e = this.eye;
    for (let k = 0; k < 4; k++) {
      const mx = (s[2 * k] + s[(2 * k + 2) & 7]) >> 1, my = (s[2 * k + 1] + s[(2 * k + 3) & 7]) >> 1;
      if (!this.inGrid(mx, my)) continue;
      const c = my * w + mx;
      const step = this.stepOf[c];
      if (this.active[c] || step === 255 || this.isCorner(mx, my)) continue;
      const gf = this.diamond(mx, my, g);
      const o = gf & (1 << 29) ? 2 : 0;
      const other = g[o] === x && g[o + 1] === y ? o + 4 : o;
      if (this.present(g[other], g[other + 1])) continue;
      const bound = this.bounds[step];
      if (bound === 0) continue; // exact: never needs a split
      this.sphereOf(c, gf, g, bound);
      const dT = (bound * this.K) / this.targetPx;
      const dx = e[0] - (mx - (w - 1) / 2) * this.cellX;
      const dy = e[1] - ((this.h - 1) / 2 - my) * this.cellY;
      const dz = e[2] - this.sphereZ;
      const slack = Math.sqrt(dx * dx + dy * dy + dz * dz) - this.sphereR - dT;
      this.queue.push(c, this.travel + Math.max(slack, 0), 1, this.sphereZ, this.sphereR, dT);
    }
  }

  /** True when one of i's child points is split. */
  hasActiveChild(i) {
    const x = i % this.w, y = (i / this.w) | 0;
    const s = this.scratch;
    return this.childActiveIn(this.diamond(x, y, s), s);
  }

  /** True when a child point of the diamond `f`, `s` is split. */
  childActiveIn(f, s) {
    if ((f & (1 << 30)) === 0 && (f & 0xffffff) === 1) return false;
    for (let k = 0; k < 4; k++) {
      const mx = (s[2 * k] + s[(2 * k + 2) & 7]) >> 1, my = (s[2 * k + 1] + s[(2 * k + 3) & 7]) >> 1;
      if (this.inGrid(mx, my) && this.active[my * this.w + mx]) return true;
    }
    return false;
  }

  /**
   * Merges i (split, not in step 0, no split child): its diamond comes back.
   * The caller schedules i as a split candidate.
   */
  merge(i) {
    const w = this.w;
    const x = i % w, y = (i / w) | 0;
    const s = this.scratch4;
    const f = this.diamond(x, y, s);
    const o = f & (1 << 29) ? 2 : 0;
    const e = 2 - o;
    const c1x = s[o], c1y = s[o + 1], c2x = s[o + 4], c2y = s[o + 5];
    const ax = s[e], ay = s[e + 1], bx = s[e + 4], by = s[e + 5];
    this.active[i] = 0;
    this.merges++;
    const ends = this.inGrid(ax, ay) && this.inGrid(bx, by);
    const use1 = ends && this.inGrid(c1x, c1y) && !this.isCorner(c1x, c1y);
    const use2 = ends && this.inGrid(c2x, c2y) && !this.isCorner(c2x, c2y);
    if (use1) this.addTri((c1y * w + c1x) * 4 + edgeIndex(x - c1x, y - c1y), c1x, c1y, ax, ay, bx, by, -1);
    if (use2) this.addTri((c2y * w + c2x) * 4 + edgeIndex(x - c2x, y - c2y), c2x, c2y, ax, ay, bx, by, -1);
    if (i === this.rootMid && this.rootsInside) this.addRoots();
    for (let k = 0; k < 4; k++) this.removeTri(i * 4 + k);
    // An apex whose last split child this was may merge now.
    const q = this.queue;
    const a1 = c1y * w + c1x, a2 = c2y * w + c2x;
    if (use1 && this.active[a1] === 1 && !this.hasActiveChild(a1)) q.push(a1, this.travel, 0, 0, 0, 0);
    if (use2 && this.active[a2] === 1 && !this.hasActiveChild(a2)) q.push(a2, this.travel, 0, 0, 0, 0);
    // i's child points whose triangles went with it are no longer candidates.
    if ((f & (1 << 30)) === 0 && (f & 0xffffff) === 1) return;
    for (let k = 0; k < 4; k++) {
      const mx = (s[2 * k] + s[(2 * k + 2) & 7]) >> 1, my = (s[2 * k + 1] + s[(2 * k + 3) & 7]) >> 1;
      if (this.inGrid(mx, my) && !this.isCandidate(my * w + mx)) q.remove(my * w + mx);
    }
  }

  // ---- the criterion ------------------------------------------------------

  /** Distance in metres from the eye to a sphere around i's diamond. */
  distance(i, bound) {
    const x = i % this.w, y = (i / this.w) | 0;
    const s = this.scratch;
    return this.distanceOf(i, x, y, this.diamond(x, y, s), s, bound);
  }

  /** `distance` with the diamond `f`, `s` of (x, y) already computed. */
  distanceOf(i, x, y, f, s, bound) {
    this.sphereOf(i, f, s, bound);
    const e = this.eye;
    const dx = e[0] - (x - (this.w - 1) / 2) * this.cellX;
    const dy = e[1] - ((this.h - 1) / 2 - y) * this.cellY;
    const dz = e[2] - this.sphereZ;
    return Math.sqrt(dx * dx + dy * dy + dz * dz) - this.sphereR;
  }

  /**
   * The sphere around i's diamond `f`, `s` (its grid samples and `bound`
   * above and below them) into this.sphereZ (centre height) and sphereR.
   */
  sphereOf(i, f, s, bound) {
    const t = f & 0xffffff;
    const { w, h, z } = this;
    let zmin = z[i], zmax = zmin;
    for (let k = 0; k < 8; k += 2) {
      const vx = s[k], vy = s[k + 1];
      if (vx < 0 || vy < 0 || vx >= w || vy >= h) continue;
      const v = z[vy * w + vx];
      if (v < zmin) zmin = v;
      else if (v > zmax) zmax = v;
    }
    const rh = (f & (1 << 30) ? t * SQRT2 : t) * this.cell;
    const rz = (zmax - zmin) / 2 + bound;
    this.sphereZ = (zmin + zmax) / 2;
    this.sphereR = Math.sqrt(rh * rh + rz * rz);
  }

  /** Screen-space error in pixels of leaving i's diamond unsplit, with `bound`. */
  screenError(i, bound) {
    if (bound === 0) return 0;
    const d = this.distance(i, bound);
    return d <= 0 ? Infinity : (bound * this.K) / d;
  }

  /**
   * Decides for i from the grid (its state, its diamond's sphere and bound),
   * and acts or schedules it again where its slack runs out.
   */
  evaluate(i) {
    this.evaluations++;
    this.fullEvaluations++;
    const a = this.active[i];
    if (a === 2) return;
    const step = this.stepOf[i];
    if (step === 255) return;
    const x = i % this.w, y = (i / this.w) | 0;
    const s = this.scratch;
    const f = this.diamond(x, y, s);
    if (a === 0) {
      if (this.isCorner(x, y)) return;
      const o = f & (1 << 29) ? 2 : 0;
      const root = i === this.rootMid && this.rootsInside;
      if (!root && !this.present(s[o], s[o + 1]) && !this.present(s[o + 4], s[o + 5])) return;
    } else if (this.childActiveIn(f, s)) {
      return; // scheduled again when its last split child merges
    }
    const bound = this.bounds[step];
    if (bound === 0) {
      if (a === 1) this.merge(i);
      return; // exact: never needs a split
    }
    this.sphereOf(i, f, s, bound);
    // At this distance from the sphere the diamond's screen error is the target.
    const dT = (bound * this.K) / this.targetPx;
    this.decide(i, a + 1, this.sphereZ, this.sphereR, dT);
  }

  /**
   * The decision for candidate i of `kind` (1: may split, 2: may merge) from
   * its sphere (centre height cz, radius r) and target distance dT: acts, or
   * schedules it again at the travel where its decision can change (the
   * distance to the sphere changes no faster than the eye moves). A split
   * candidate splits when nearer than dT / SPLIT_FRACTION, a split point merges
   * beyond dT / MERGE_FRACTION.
   */
  decide(i, kind, cz, r, dT) {
    const e = this.eye;
    const y = (i / this.w) | 0, x = i - y * this.w;
    const dx = e[0] - (x - (this.w - 1) / 2) * this.cellX;
    const dy = e[1] - ((this.h - 1) / 2 - y) * this.cellY;
    const dz = e[2] - cz;
    const D = Math.sqrt(dx * dx + dy * dy + dz * dz);
    const t = this.travel;
    if (kind === 1) {
      const key = t + (D - r - dT);
      if (D - r < dT / SPLIT_FRACTION || !(key > t)) {
        this.split(i);
        // Now a merge candidate, its slack known (D − r < dT < dT / MERGE_FRACTION).
        this.queue.push(i, t + (r + dT / MERGE_FRACTION - D), 2, cz, r, dT);
      } else {
        this.queue.push(i, key, 1, cz, r, dT);
      }
    } else {
      const key = t + (r + dT / MERGE_FRACTION - D);
      if (key > t) {
        this.queue.push(i, key, 2, cz, r, dT);
      } else {
        this.merge(i);
        this.queue.push(i, t + (D - r - dT), 1, cz, r, dT);
      }
    }
  }

  /**
   * Moves the eye and remeshes: takes out every candidate whose slack is used
   * up. `K` = viewport height in pixels / (2 tan(fovY / 2)). Stops before
   * `budgetMs` would be passed, judging the next slice of CLOCK_EVERY
   * candidates by the last (the rest waits for the next frame). Returns the
   * number of candidates evaluated.
   */
  update(eye, K, targetPx, budgetMs = FRAME_BUDGET_MS) {
    this.frame++;
    if (this.eye) {
      const dx = eye[0] - this.eye[0], dy = eye[1] - this.eye[1], dz = eye[2] - this.eye[2];
      this.travel += Math.sqrt(dx * dx + dy * dy + dz * dz);
    }
    this.eye = [eye[0], eye[1], eye[2]];
    if (K !== this.K || targetPx !== this.targetPx) {
      this.K = K;
      this.targetPx = targetPx;
      this.rescheduleAll();
    }
    const q = this.queue;
    const t0 = performance.now();
    let tLast = t0;
    let n = 0;
    this.pending = false;
    q.begin(this.travel);
    for (;;) {
      const got = q.popDue(this.travel, SCAN_EVERY);
      if (got === 0) break;
      if (got === 1) {
        const i = q.node;
        if (q.kind === 0) {
          this.evaluate(i);
        } else {
          // The entry carries the decision's constants: no look at the grid
          // unless the decision acts.
          this.evaluations++;
          this.decide(i, q.kind, q.cz, q.r, q.dT);
        }
        if (++n % CLOCK_EVERY !== 0) continue;
      }
      // Stop when the next slice, as long as the last, would end past the budget.
      const now = performance.now();
      if (2 * now - t0 - tLast > budgetMs) {
        this.pending = true;
        break;
      }
      tLast = now;
    }
    return n;
  }

  /** Every candidate is decided again at once (new viewport or target). */
  rescheduleAll() {
    for (let i = 0; i < this.w * this.h; i++) {
      if (this.active[i] === 1 || this.isCandidate(i)) this.queue.push(i, this.travel, 0, 0, 0, 0);
    }
  }

  // ---- measures -----------------------------------------------------------

  /**
   * The exact largest screen error over the mesh's leaves now: `sent` over
   * leaves whose split point has arrived (what refinement controls), `all`
   * also counting leaves cut short by the stream so far (bounded by the
   * latest stated error).
   */
  maxScreenError() {
    let sent = 0, all = 0;
    const latest = this.latestStated();
    const s = new Int32Array(8);
    for (let slot = 0; slot < this.triTop; slot++) {
      const key = this.triKey[slot];
      if (key < 0) continue;
      const m = this.leafSplitPoint(key, s);
      if (m < 0) continue;
      if (this.stepOf[m] === 255) {
        all = Math.max(all, this.screenError(m, latest));
      } else {
        const e = this.screenError(m, this.bounds[this.stepOf[m]]);
        sent = Math.max(sent, e);
        all = Math.max(all, e);
      }
    }
    return { sent, all };
  }

  /** Split point of leaf `key`, or −1 for a unit triangle. */
  leafSplitPoint(key, s) {
    const len = this.w * this.h;
    if (key >= len * 4) return this.rootMid;
    const c = Math.floor(key / 4), k = key & 3;
    const x = c % this.w, y = (c / this.w) | 0;
    const f = this.diamond(x, y, s);
    if ((f & (1 << 30)) === 0 && (f & 0xffffff) === 1) return -1;
    const mx = (s[2 * k] + s[(2 * k + 2) & 7]) >> 1, my = (s[2 * k + 1] + s[(2 * k + 3) & 7]) >> 1;
    return my * this.w + mx;
  }

  /** The leaves as sample-index triples (for tests). */
  leafTriangles() {
    const out = [];
    for (let slot = 0; slot < this.triTop; slot++) {
      if (this.triKey[slot] < 0) continue;
      out.push([this.triSamples[slot * 3], this.triSamples[slot * 3 + 1], this.triSamples[slot * 3 + 2]]);
    }
    return out;
  }
}
