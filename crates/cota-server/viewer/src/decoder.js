// Decoder of cota's progressive stream (`.cstream`, error-steps kind) in
// JavaScript, for the viewer's Web Worker and for node.
//
// Paper 000 (../../../../shared/seeds/000_ebf7e3a88dffd361.txt, §3
// "Transmisión progresiva"): the coarse mesh first, then the points each finer
// tolerance adds; the receiver rebuilds the hierarchy itself. This file mirrors
// the Rust decoder bit for bit:
//   * framing: crates/cota-io/src/stream_file.rs (magic, version, head, CRC-32
//     per step);
//   * header, walk, contexts, height prediction: crates/cota-core/src/stream.rs;
//   * range coder and residual binarisation: crates/cota-core/src/stream_coder.rs.
// The node tests (test/decoder.test.mjs) decode golden streams written by the
// Rust side and compare every step's mesh and heights with the Rust decoder's.
//
// Only error-steps streams (kind 0, what `cota serve` sends) are decoded: every
// split point there carries its height. Marks streams (kinds 1–3) are refused.

const PROB_BITS = 12;
const PROB_HALF = 1 << (PROB_BITS - 1);
const ADAPT = 5;
const TOP = 1 << 24;
const MAX_BITS = 48;
const LEVELS = 64;
const STEPS = 16;
const MAX_Q = 2 ** 40;
const RESIDUAL_SLOTS = 2 + 2 * MAX_BITS;
export const HEADER_BYTES = 52;
export const MAGIC = 'COTASTRM';
export const VERSION = 1;
const MAX_HEAD = 1 << 16;
const MAX_STEP = 2 ** 31;
/** Largest grid the viewer decodes (samples). */
export const MAX_SAMPLES = 1 << 27;

/** A stream that does not decode. */
export class StreamError extends Error {
  constructor(message) {
    super(message);
    this.name = 'StreamError';
  }
}

const CRC_TABLE = (() => {
  const t = new Uint32Array(256);
  for (let i = 0; i < 256; i++) {
    let c = i;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    t[i] = c >>> 0;
  }
  return t;
})();

/** CRC-32 (IEEE) of `bytes`. */
export function crc32(bytes) {
  let c = 0xffffffff;
  for (let i = 0; i < bytes.length; i++) c = CRC_TABLE[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

/** Adaptive binary range decoder over one coded block (stream_coder.rs). */
class RangeDecoder {
  constructor(data) {
    this.data = data;
    this.pos = 0;
    this.code = 0;
    this.range = 0xffffffff;
    this.overrun = 0;
    for (let i = 0; i < 5; i++) this.code = ((this.code << 8) | this.next()) >>> 0;
  }

  next() {
    if (this.pos < this.data.length) return this.data[this.pos++];
    this.overrun++;
    return 0;
  }

  /** One bit under the adaptive probability `probs[i]` (of a 0), then adapts it. */
  bit(probs, i) {
    const p = probs[i];
    const bound = (this.range >>> PROB_BITS) * p;
    let bit;
    if (this.code < bound) {
      this.range = bound;
      bit = 0;
      probs[i] = p + (((1 << PROB_BITS) - p) >> ADAPT);
    } else {
      this.code -= bound;
      this.range -= bound;
      bit = 1;
      probs[i] = p - (p >> ADAPT);
    }
    while (this.range < TOP) {
      this.range = (this.range << 8) >>> 0;
      this.code = ((this.code << 8) | this.next()) >>> 0;
    }
    return bit;
  }

  /** One bit at a fixed probability of 1/2. */
  bypass() {
    const bound = (this.range >>> PROB_BITS) * PROB_HALF;
    let bit;
    if (this.code < bound) {
      this.range = bound;
      bit = 0;
    } else {
      this.code -= bound;
      this.range -= bound;
      bit = 1;
    }
    while (this.range < TOP) {
      this.range = (this.range << 8) >>> 0;
      this.code = ((this.code << 8) | this.next()) >>> 0;
    }
    return bit;
  }

  /** A signed residual of context `ctx` (ResidualModel::decode). */
  residual(models, ctx) {
    const base = ctx * RESIDUAL_SLOTS;
    if (!this.bit(models, base)) return 0;
    const negative = this.bit(models, base + 1);
    let n = 1;
    while (n < MAX_BITS && this.bit(models, base + 2 + n - 1)) n++;
    let a = 1;
    if (n >= 2) {
      a = a * 2 + this.bit(models, base + 2 + MAX_BITS + n - 1);
      for (let k = 0; k < n - 2; k++) a = a * 2 + this.bypass();
    }
    return negative ? -a : a;
  }
}

/** Trailing zeros of a positive 32-bit integer. */
function ctz(v) {
  return 31 - Math.clz32(v & -v);
}

/** Side of the padded square: smallest power of two ≥ max(W−1, H−1). */
export function paddedSize(width, height) {
  const span = Math.max(Math.max(width, height) - 1, 1);
  let n = 1;
  while (n < span) n *= 2;
  return n;
}

/** Parses the 52-byte core header (StreamHeader::from_bytes). */
export function parseHeader(b) {
  if (b.length !== HEADER_BYTES) {
    throw new StreamError(`bad stream header: expected ${HEADER_BYTES} bytes, found ${b.length} bytes`);
  }
  const dv = new DataView(b.buffer, b.byteOffset, b.byteLength);
  const width = dv.getUint32(0, true);
  const height = dv.getUint32(4, true);
  const ok = (v) => v >= 2 && v <= 2 ** 30;
  if (!ok(width) || !ok(height) || width * height > 2 ** 31) {
    throw new StreamError(`bad stream header: expected a grid of 2..2^30 samples per side and at most 2^31 samples, found ${width}x${height}`);
  }
  const quantum = dv.getFloat64(8, true);
  if (!(Number.isFinite(quantum) && quantum > 0)) {
    throw new StreamError(`bad stream header: expected a positive finite quantum, found ${quantum}`);
  }
  const corners = [];
  for (let k = 0; k < 4; k++) {
    const c = dv.getBigInt64(16 + 8 * k, true);
    if (c >= BigInt(MAX_Q) || c <= -BigInt(MAX_Q)) {
      throw new StreamError(`bad stream header: expected corner heights below 2^40 quanta, found ${c}`);
    }
    corners.push(Number(c));
  }
  const kind = dv.getUint32(48, true);
  if (kind > 3) throw new StreamError(`bad stream header: expected a stream kind of 0 to 3, found ${kind}`);
  return { width, height, quantum, corners, kind };
}

/**
 * The receiver of an error-steps stream: applies steps, keeps every split
 * decision, height and the step each point was split in.
 */
export class StreamDecoder {
  constructor(header) {
    if (header.kind !== 0) {
      throw new StreamError(`expected an error-steps stream (kind 0), found kind ${header.kind} (marks streams are not decoded by the viewer)`);
    }
    const { width: w, height: h } = header;
    if (w * h > MAX_SAMPLES) {
      throw new StreamError(`expected a grid of at most ${MAX_SAMPLES} samples for the viewer, found ${w}x${h}`);
    }
    this.header = header;
    this.w = w;
    this.h = h;
    this.n = paddedSize(w, h);
    const len = w * h;
    this.split = new Uint8Array(len);
    this.decided = new Uint32Array(len);
    this.epoch = 0;
    this.q = new Float64Array(len).fill(NaN);
    /** Step in which each sample was split (255: not yet). */
    this.stepOf = new Uint8Array(len).fill(255);
    this.journal = [];
    this.learned = 0;
    this.splitModels = new Uint16Array(LEVELS * STEPS * 2).fill(PROB_HALF);
    this.residualModels = new Uint16Array(LEVELS * STEPS * RESIDUAL_SLOTS).fill(PROB_HALF);
    this.steps = [];
    const n = this.n;
    [[0, 0], [n, 0], [0, n], [n, n]].forEach(([x, y], k) => {
      if (x < w && y < h) this.q[y * w + x] = header.corners[k];
    });
    this.stack = new Int32Array(7 * 256);
  }

  /** The stated max error of the current prefix (undefined before step 0). */
  maxErrorM() {
    return this.steps.length ? this.steps[this.steps.length - 1].maxErrorM : undefined;
  }

  /**
   * Applies one step payload. On error the decoder keeps the previous prefix.
   * Returns { index, maxErrorM, newPoints, points: Int32Array of the samples
   * split in this step }.
   */
  applyStep(payload) {
    const index = this.steps.length;
    if (payload.length < 4) {
      throw new StreamError(`step ${index}: expected at least 4 bytes, found ${payload.length} bytes`);
    }
    const stated = new DataView(payload.buffer, payload.byteOffset, 4).getFloat32(0, true);
    const prev = index ? this.steps[index - 1].maxErrorM : Infinity;
    if (!(stated >= 0 && stated <= prev)) {
      throw new StreamError(`step ${index}: expected a stated max error between 0 m and ${prev} m, found ${stated} m`);
    }
    const block = payload.subarray(4);
    const savedSplit = this.splitModels.slice();
    const savedResidual = this.residualModels.slice();
    const dec = new RangeDecoder(block);
    this.epoch++;
    this.journal = [];
    this.learned = 0;
    let failure = null;
    try {
      this.walkStep(dec, index);
      if (dec.overrun > 0) {
        failure = `step ${index}: expected ${block.length + dec.overrun} bytes of coded data, found ${block.length} (truncated or corrupted)`;
      }
    } catch (e) {
      failure = e instanceof StreamError ? e.message : String(e);
    }
    if (failure) {
      for (const i of this.journal) {
        this.split[i] = 0;
        this.q[i] = NaN;
      }
      this.journal = [];
      this.splitModels = savedSplit;
      this.residualModels = savedResidual;
      throw new StreamError(failure);
    }
    const points = Int32Array.from(this.journal);
    for (const i of points) this.stepOf[i] = index;
    const info = { index, maxErrorM: stated, newPoints: this.learned, payloadBytes: payload.length, points };
    this.steps.push({ index, maxErrorM: stated, newPoints: this.learned, payloadBytes: payload.length });
    this.journal = [];
    return info;
  }

  /** The height in metres of sample `i` (NaN when not known). */
  heightM(i) {
    return Math.fround(this.q[i] * this.header.quantum);
  }

  walkStep(dec, step) {
    const n = this.n;
    // Roots: (0,0)-(N,N) with apex (N,0), then (N,N)-(0,0) with apex (0,N).
    this.walk(dec, step, [n, n, 0, 0, 0, n, 0, 0, 0, n, n, n, 0, 0]);
  }

  /**
   * Depth-first walk in Tri::children order with an explicit stack of
   * (ax, ay, bx, by, cx, cy, inside); `roots` holds two such entries, the
   * second first (popped last).
   */
  walk(dec, step, roots) {
    const { w, h, split, decided, q } = this;
    let st = this.stack;
    let sp = 0;
    for (let k = 0; k < 14; k++) st[sp++] = roots[k];
    while (sp > 0) {
      sp -= 7;
      const ax = st[sp], ay = st[sp + 1], bx = st[sp + 2], by = st[sp + 3];
      const cx = st[sp + 4], cy = st[sp + 5];
      let inside = st[sp + 6];
      if (!inside) {
        if (ax < w && ay < h && bx < w && by < h && cx < w && cy < h) {
          inside = 1;
        } else {
          const lx = Math.min(ax, bx, cx), ly = Math.min(ay, by, cy);
          if (lx >= w - 1 || ly >= h - 1) continue; // outside
        }
      }
      const dx = Math.abs(ax - bx), dy = Math.abs(ay - by);
      if (dx === 1 && dy === 1) continue; // unit triangle
      const mx = (ax + bx) >> 1, my = (ay + by) >> 1;
      if (!inside) {
        if (mx < w && my < h) {
          const i = my * w + mx;
          if (!split[i]) {
            split[i] = 1;
            decided[i] = this.epoch;
            this.journal.push(i);
          }
          if (Number.isNaN(q[i])) this.learn(dec, step, ax, ay, bx, by, cx, cy, i);
        }
      } else {
        const i = my * w + mx;
        if (!split[i]) {
          if (decided[i] === this.epoch) continue;
          const fresh = cx < w && cy < h && decided[cy * w + cx] === this.epoch ? 1 : 0;
          const lvl = level(dx, dy);
          decided[i] = this.epoch;
          const ctx = (lvl * STEPS + Math.min(step, STEPS - 1)) * 2 + fresh;
          if (!dec.bit(this.splitModels, ctx)) continue;
          split[i] = 1;
          this.journal.push(i);
          if (Number.isNaN(q[i])) this.learn(dec, step, ax, ay, bx, by, cx, cy, i);
        }
      }
      if (sp + 14 > st.length) {
        const bigger = new Int32Array(st.length * 2);
        bigger.set(st);
        this.stack = st = bigger;
      }
      // Push child 1 {a: b, b: c, c: m}, then child 0 {a: c, b: a, c: m}.
      st[sp] = bx; st[sp + 1] = by; st[sp + 2] = cx; st[sp + 3] = cy;
      st[sp + 4] = mx; st[sp + 5] = my; st[sp + 6] = inside;
      st[sp + 7] = cx; st[sp + 8] = cy; st[sp + 9] = ax; st[sp + 10] = ay;
      st[sp + 11] = mx; st[sp + 12] = my; st[sp + 13] = inside;
      sp += 14;
    }
  }

  /** Decodes the height of split point `i` of triangle (a, b, c). */
  learn(dec, step, ax, ay, bx, by, cx, cy, i) {
    const { w, h, q } = this;
    const known = (x, y) => (x < w && y < h ? q[y * w + x] : NaN);
    const qa = known(ax, ay), qb = known(bx, by);
    let pred;
    if (!Number.isNaN(qa) && !Number.isNaN(qb)) {
      pred = Math.floor((qa + qb) / 2);
    } else {
      let sum = 0, count = 0;
      for (const v of [qa, qb, known(cx, cy)]) {
        if (!Number.isNaN(v)) {
          sum += v;
          count++;
        }
      }
      pred = count ? Math.floor(sum / count) : 0;
    }
    const lvl = level(Math.abs(ax - bx), Math.abs(ay - by));
    const r = dec.residual(this.residualModels, lvl * STEPS + Math.min(step, STEPS - 1));
    const v = pred + r;
    if (!(Math.abs(v) < MAX_Q)) {
      throw new StreamError(`a height below 2^40 quanta, found a residual of ${r} on a prediction of ${pred}`);
    }
    q[i] = v;
    this.learned++;
  }

  /**
   * The current mesh as Rust's StreamDecoder::mesh gives it: leaves
   * counter-clockwise from above, vertices numbered row-major.
   * Returns { vertices: Int32Array [col, row, ...], heights: Float32Array,
   * triangles: Uint32Array }.
   */
  mesh() {
    const { w } = this;
    const tris = [];
    this.leaves((ax, ay, bx, by, cx, cy) => {
      // orient_up in the east/north frame (y = −row).
      const o = (bx - ax) * (-cy + ay) - (-by + ay) * (cx - ax);
      if (o > 0) tris.push(ay * w + ax, by * w + bx, cy * w + cx);
      else tris.push(by * w + bx, ay * w + ax, cy * w + cx);
    });
    const used = new Int32Array(this.split.length).fill(-1);
    for (const i of tris) used[i] = 0;
    const cols = [];
    const heights = [];
    let next = 0;
    for (let i = 0; i < used.length; i++) {
      if (used[i] === 0) {
        used[i] = next++;
        cols.push(i % w, Math.floor(i / w));
        heights.push(this.heightM(i));
      }
    }
    return {
      vertices: Int32Array.from(cols),
      heights: Float32Array.from(heights),
      triangles: Uint32Array.from(tris, (i) => used[i]),
    };
  }

  /**
   * Every sample's height as the current prefix's surface gives it
   * (StreamDecoder::heights_m): sent heights exactly, the others interpolated
   * on their leaf, snapped to the lattice when the stated error is below half
   * a quantum. A Float32Array, or undefined before step 0.
   */
  heightsM() {
    const stated = this.maxErrorM();
    if (stated === undefined) return undefined;
    const qm = this.header.quantum;
    const snap = stated < qm / 2;
    const { w } = this;
    const z = Float64Array.from(this.q, (v) => v * qm);
    const roundAway = (x) => Math.sign(x) * Math.round(Math.abs(x));
    this.leaves((ax, ay, bx, by, cx, cy) => {
      const stack = [[ax, ay, bx, by, cx, cy]];
      while (stack.length) {
        const [px, py, qx, qy, rx, ry] = stack.pop();
        if (Math.abs(px - qx) === 1 && Math.abs(py - qy) === 1) continue;
        const mx = (px + qx) >> 1, my = (py + qy) >> 1;
        const i = my * w + mx;
        if (Number.isNaN(z[i])) {
          const v = (z[py * w + px] + z[qy * w + qx]) / 2;
          z[i] = snap ? roundAway(v / qm) * qm : v;
        }
        stack.push([rx, ry, px, py, mx, my]);
        stack.push([qx, qy, rx, ry, mx, my]);
      }
    });
    return Float32Array.from(z);
  }

  /** Calls f(ax, ay, bx, by, cx, cy) for each leaf of the current mesh. */
  leaves(f) {
    const { w, h, n, split } = this;
    const stack = [[n, n, 0, 0, 0, n, 0], [0, 0, n, n, n, 0, 0]];
    while (stack.length) {
      const [ax, ay, bx, by, cx, cy, ins] = stack.pop();
      let inside = ins;
      if (!inside) {
        if (ax < w && ay < h && bx < w && by < h && cx < w && cy < h) inside = 1;
        else if (Math.min(ax, bx, cx) >= w - 1 || Math.min(ay, by, cy) >= h - 1) continue;
      }
      const unit = Math.abs(ax - bx) === 1 && Math.abs(ay - by) === 1;
      if (unit) {
        if (inside) f(ax, ay, bx, by, cx, cy);
        continue;
      }
      const mx = (ax + bx) >> 1, my = (ay + by) >> 1;
      if (inside && !split[my * w + mx]) {
        f(ax, ay, bx, by, cx, cy);
        continue;
      }
      stack.push([bx, by, cx, cy, mx, my, inside]);
      stack.push([cx, cy, ax, ay, mx, my, inside]);
    }
  }
}

/** Context level of a triangle whose hypotenuse spans (dx, dy). */
function level(dx, dy) {
  const s = Math.max(dx, dy);
  const a = dx !== 0 && dy !== 0 ? 1 : 0;
  return Math.min(2 * ctz(s) + a, LEVELS - 1);
}

/** Parses the framed head (after magic, version and length). */
function parseHead(b) {
  const fixed = HEADER_BYTES + 4 + 2 + 32 + 1;
  if (b.length < fixed) {
    throw new StreamError(`bad stream head: expected at least ${fixed} bytes, found ${b.length} bytes`);
  }
  const header = parseHeader(b.subarray(0, HEADER_BYTES));
  const dv = new DataView(b.buffer, b.byteOffset, b.byteLength);
  const steps = dv.getUint32(HEADER_BYTES, true);
  const g = HEADER_BYTES + 4;
  const georef = {
    known: b[g] !== 0,
    pixelIsPoint: b[g + 1] !== 0,
    originX: dv.getFloat64(g + 2, true),
    originY: dv.getFloat64(g + 10, true),
    pixelX: dv.getFloat64(g + 18, true),
    pixelY: dv.getFloat64(g + 26, true),
    crs: null,
  };
  const vals = [georef.originX, georef.originY, georef.pixelX, georef.pixelY];
  if (!vals.every(Number.isFinite) || georef.pixelX === 0 || georef.pixelY === 0) {
    throw new StreamError(`bad stream georeference: expected finite origin and non-zero finite pixel size, found ${vals.join(', ')}`);
  }
  const kind = b[fixed - 1];
  const rest = b.subarray(fixed);
  if (kind === 1) {
    if (rest.length !== 4) throw new StreamError(`bad stream head: expected ${fixed + 4} bytes, found ${b.length}`);
    georef.crs = { epsg: dv.getUint32(fixed, true) };
  } else if (kind === 2 || kind === 3 || kind === 4) {
    if (rest.length < 2) throw new StreamError(`bad stream head: expected ${fixed + 2} bytes, found ${b.length}`);
    const len = rest[0] | (rest[1] << 8);
    if (rest.length !== 2 + len) throw new StreamError(`bad stream head: expected ${fixed + 2 + len} bytes, found ${b.length}`);
    georef.crs = { [['geographic', 'projected', 'proj'][kind - 2]]: new TextDecoder().decode(rest.subarray(2)) };
  } else if (kind !== 0) {
    throw new StreamError(`bad stream CRS: expected kind 0, 1, 2, 3 or 4 (a PROJ definition), found kind ${kind}`);
  }
  return { header, steps, georef };
}

/**
 * Incremental reader of a framed stream: push byte chunks as they arrive and
 * get each step back as soon as its frame is complete and its CRC matches.
 */
export class StreamReader {
  constructor() {
    this.buf = new Uint8Array(0);
    this.start = 0;
    this.end = 0;
    this.offset = 0;
    this.decoder = null;
    this.georef = null;
    this.announced = 0;
  }

  append(chunk) {
    if (this.end + chunk.length > this.buf.length) {
      const live = this.end - this.start;
      const cap = Math.max(2 * (live + chunk.length), 1 << 16);
      const b = new Uint8Array(cap);
      b.set(this.buf.subarray(this.start, this.end));
      this.buf = b;
      this.start = 0;
      this.end = live;
    }
    this.buf.set(chunk, this.end);
    this.end += chunk.length;
  }

  /** Appends `chunk`; returns the steps completed (with their end offsets). */
  push(chunk) {
    this.append(chunk);
    const out = [];
    for (;;) {
      const f = this.nextFrame();
      if (f === null) return out;
      if (f !== undefined) out.push(f);
    }
  }

  /** Bytes of complete frames consumed so far. */
  consumed() {
    return this.offset;
  }

  nextFrame() {
    const b = this.buf.subarray(this.start, this.end);
    if (!this.decoder) return this.readHead(b);
    if (b.length < 8) return null;
    const dv = new DataView(b.buffer, b.byteOffset, b.byteLength);
    const len = dv.getUint32(0, true);
    if (len > MAX_STEP) throw new StreamError(`bad stream step: expected at most ${MAX_STEP} bytes, found ${len} bytes`);
    if (b.length < 8 + len) return null;
    const crc = dv.getUint32(4, true);
    const payload = b.slice(8, 8 + len);
    const step = this.decoder.steps.length;
    if (step >= this.announced) {
      throw new StreamError(`bad stream steps: expected ${this.announced} steps as announced, found more`);
    }
    const found = crc32(payload);
    if (found !== crc) {
      throw new StreamError(`corrupted stream: step ${step} has CRC-32 ${found.toString(16)}, expected ${crc.toString(16)}`);
    }
    const info = this.decoder.applyStep(payload);
    this.start += 8 + len;
    this.offset += 8 + len;
    info.endOffset = this.offset;
    return info;
  }

  readHead(b) {
    const n = Math.min(b.length, 8);
    for (let i = 0; i < n; i++) {
      if (b[i] !== MAGIC.charCodeAt(i)) {
        throw new StreamError(`expected a cota stream starting with "COTASTRM", found ${JSON.stringify(new TextDecoder().decode(b.subarray(0, n)))}`);
      }
    }
    if (b.length < 14) return null;
    const dv = new DataView(b.buffer, b.byteOffset, b.byteLength);
    const version = dv.getUint16(8, true);
    if (version !== VERSION) throw new StreamError(`expected stream format version ${VERSION}, found ${version}`);
    const len = dv.getUint32(10, true);
    if (len > MAX_HEAD) throw new StreamError(`bad stream head: expected at most ${MAX_HEAD} bytes, found ${len} bytes`);
    if (b.length < 18 + len) return null;
    const head = b.slice(14, 14 + len);
    const crc = dv.getUint32(14 + len, true);
    const found = crc32(head);
    if (found !== crc) {
      throw new StreamError(`corrupted stream: head has CRC-32 ${found.toString(16)}, expected ${crc.toString(16)}`);
    }
    const { header, steps, georef } = parseHead(head);
    this.decoder = new StreamDecoder(header);
    this.georef = georef;
    this.announced = steps;
    this.start += 18 + len;
    this.offset += 18 + len;
    return undefined;
  }

  /** Throws unless every announced step arrived and no partial frame is left. */
  finish() {
    if (!this.decoder) throw new StreamError('truncated stream: the head did not arrive');
    if (this.end > this.start) throw new StreamError(`truncated stream: ${this.end - this.start} bytes of a partial frame`);
    if (this.decoder.steps.length < this.announced) {
      throw new StreamError(`truncated stream: expected ${this.announced} steps, found ${this.decoder.steps.length}`);
    }
  }
}
