// The JavaScript stream decoder against the Rust decoder: golden streams and
// what Rust made of each of their steps (written by
// crates/cota-server/tests/golden.rs), plus truncation and corruption.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, readdirSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import { dirname, join } from 'node:path';
import { StreamReader, StreamError, crc32 } from '../src/decoder.js';

const golden = join(dirname(fileURLToPath(import.meta.url)), 'golden');
const names = readdirSync(golden).filter((f) => f.endsWith('.cstream')).map((f) => f.slice(0, -8));

function fnv(bytes) {
  let h = 0xcbf29ce484222325n;
  for (const b of bytes) {
    h ^= BigInt(b);
    h = (h * 0x100000001b3n) & 0xffffffffffffffffn;
  }
  return h.toString(16).padStart(16, '0');
}

function meshBytes(m) {
  const nv = m.vertices.length / 2;
  const buf = new ArrayBuffer(nv * 12 + m.triangles.length * 4);
  const dv = new DataView(buf);
  for (let v = 0; v < nv; v++) {
    dv.setUint32(v * 12, m.vertices[2 * v], true);
    dv.setUint32(v * 12 + 4, m.vertices[2 * v + 1], true);
    dv.setFloat32(v * 12 + 8, m.heights[v], true);
  }
  m.triangles.forEach((t, k) => dv.setUint32(nv * 12 + 4 * k, t, true));
  return new Uint8Array(buf);
}

const load = (name) => ({
  bytes: new Uint8Array(readFileSync(join(golden, `${name}.cstream`))),
  want: JSON.parse(readFileSync(join(golden, `${name}.json`), 'utf8')),
});

test('golden files exist', () => {
  assert.ok(names.length >= 5, `golden streams in ${golden}: ${names}`);
});

for (const name of names) {
  test(`${name}: every step equals the Rust decoder's`, () => {
    const { bytes, want } = load(name);
    const r = new StreamReader();
    let k = 0;
    // Feed odd-sized chunks, as they would arrive, cut at step ends so that
    // every prefix can be compared.
    const cuts = [];
    let prev = 0;
    for (const s of want.steps) {
      for (let at = prev; at < s.end_offset; at += 97) cuts.push([at, Math.min(at + 97, s.end_offset)]);
      prev = s.end_offset;
    }
    for (const [from, to] of cuts) {
      for (const info of r.push(bytes.subarray(from, to))) {
        const w = want.steps[k];
        assert.equal(info.index, w.index);
        assert.equal(info.endOffset, w.end_offset);
        assert.equal(info.maxErrorM, w.max_error_m);
        assert.equal(info.newPoints, w.new_points);
        const m = r.decoder.mesh();
        assert.equal(m.triangles.length / 3, w.triangles, `${name} step ${k} triangles`);
        assert.equal(m.vertices.length / 2, w.vertices, `${name} step ${k} vertices`);
        if (w.mesh) {
          assert.deepEqual(Array.from(m.triangles), w.mesh.triangles.flat());
          const verts = [];
          for (let v = 0; v < m.heights.length; v++) verts.push([m.vertices[2 * v], m.vertices[2 * v + 1], m.heights[v]]);
          assert.deepEqual(verts, w.mesh.vertices);
        }
        assert.equal(fnv(meshBytes(m)), w.mesh_fnv, `${name} step ${k} mesh`);
        const z = r.decoder.heightsM();
        assert.equal(fnv(new Uint8Array(z.buffer)), w.heights_fnv, `${name} step ${k} heights`);
        k++;
      }
    }
    r.finish();
    assert.equal(k, want.steps.length);
    assert.equal(r.decoder.header.width, want.width);
    assert.equal(r.decoder.header.height, want.height);
  });
}

test('a truncated stream keeps its last whole step and says what is missing', () => {
  const { bytes, want } = load('s29w072-129x97');
  const cut = want.steps[3].end_offset + 5;
  const r = new StreamReader();
  const steps = r.push(bytes.subarray(0, cut));
  assert.equal(steps.length, 4);
  assert.throws(() => r.finish(), (e) => e instanceof StreamError && /truncated/.test(e.message));
});

test('corruption is reported, never a crash, and the prefix survives', () => {
  const { bytes, want } = load('s29w072-129x97');
  // A flipped byte in step 5's payload: the CRC catches it.
  const b = bytes.slice();
  b[want.steps[4].end_offset + 12] ^= 0x40;
  const r = new StreamReader();
  assert.throws(() => r.push(b), (e) => e instanceof StreamError && /CRC-32/.test(e.message));
  assert.equal(r.decoder.steps.length, 5);
  // Bad magic, bad version.
  assert.throws(() => new StreamReader().push(new TextEncoder().encode('NOTASTREAM')), /COTASTRM/);
  const v = bytes.slice(0, 20);
  v[8] = 9;
  assert.throws(() => new StreamReader().push(v), /version/);
});

test('random payloads with valid CRCs are rejected or decoded, never a crash', () => {
  const { bytes, want } = load('synthetic-37x23');
  const headEnd = 18 + new DataView(bytes.buffer, bytes.byteOffset).getUint32(10, true) + 4;
  let x = 0x9e3779b9;
  let rejected = 0;
  for (let len = 0; len < 300; len++) {
    const payload = new Uint8Array(4 + len);
    for (let i = 4; i < payload.length; i++) {
      x ^= x << 13; x ^= x >>> 17; x ^= x << 5;
      payload[i] = x & 0xff;
    }
    const frame = new Uint8Array(8 + payload.length);
    const dv = new DataView(frame.buffer);
    dv.setUint32(0, payload.length, true);
    dv.setUint32(4, crc32(payload), true);
    frame.set(payload, 8);
    const r = new StreamReader();
    r.push(bytes.subarray(0, headEnd));
    try {
      r.push(frame);
      assert.ok(r.decoder.mesh().triangles.length >= 3);
    } catch (e) {
      assert.ok(e instanceof StreamError, String(e));
      assert.equal(r.decoder.steps.length, 0);
      rejected++;
    }
  }
  assert.ok(rejected > 0);
});

test('a head whose CRS is a PROJ definition (kind 4, as `cota serve` writes for a UTM GeoTIFF) decodes', () => {
  const { bytes, want } = load('s29w072-129x97');
  const dv = new DataView(bytes.buffer, bytes.byteOffset);
  const headLen = dv.getUint32(10, true);
  const fixed = 52 + 4 + 2 + 32 + 1;
  const proj = new TextEncoder().encode('+proj=utm +zone=25 +south +ellps=GRS80 +units=m +no_defs');
  const head = new Uint8Array(fixed + 2 + proj.length);
  head.set(bytes.subarray(14, 14 + fixed));
  head[fixed - 1] = 4;
  head[fixed] = proj.length & 0xff;
  head[fixed + 1] = proj.length >> 8;
  head.set(proj, fixed + 2);
  const rest = bytes.subarray(14 + headLen + 4);
  const out = new Uint8Array(14 + head.length + 4 + rest.length);
  out.set(bytes.subarray(0, 14));
  new DataView(out.buffer).setUint32(10, head.length, true);
  out.set(head, 14);
  new DataView(out.buffer).setUint32(14 + head.length, crc32(head), true);
  out.set(rest, 14 + head.length + 4);
  const r = new StreamReader();
  const steps = r.push(out);
  assert.equal(steps.length, want.steps.length);
  assert.match(r.georef.crs.proj, /^\+proj=utm \+zone=25/);
  head[fixed - 1] = 5;
  out.set(head, 14);
  new DataView(out.buffer).setUint32(14 + head.length, crc32(head), true);
  assert.throws(() => new StreamReader().push(out), /kind 5/);
});
