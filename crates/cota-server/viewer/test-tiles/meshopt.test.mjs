// The npm `meshoptimizer` decoder (the one CesiumJS loads) over buffers cota's
// pure-Rust meshopt encoder wrote: each decodes to exactly the input bytes.
// Environment: COTA_MESHOPT_CASES, a directory the cota-io test
// `tiles3d::meshopt::npm_decoder_reads_cota_buffers` fills with NAME.json
// ({mode, count, stride}), NAME.raw (the input) and NAME.bin (the encoded
// stream), then runs this file on. Without it the test skips.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { MeshoptDecoder } from 'meshoptimizer';

const dir = process.env.COTA_MESHOPT_CASES;
if (!dir) {
  test('npm meshoptimizer decodes cota buffers', { skip: 'set COTA_MESHOPT_CASES (cargo test -p cota-io --test suite tiles3d::meshopt)' }, () => {});
} else {
  test('npm meshoptimizer decodes cota buffers to the input', async () => {
    await MeshoptDecoder.ready;
    const names = fs.readdirSync(dir).filter((f) => f.endsWith('.json')).map((f) => f.slice(0, -5)).sort();
    assert.ok(names.length > 0, `no cases in ${dir}`);
    for (const name of names) {
      const { mode, count, stride } = JSON.parse(fs.readFileSync(path.join(dir, `${name}.json`), 'utf8'));
      const raw = new Uint8Array(fs.readFileSync(path.join(dir, `${name}.raw`)));
      const bin = new Uint8Array(fs.readFileSync(path.join(dir, `${name}.bin`)));
      const out = new Uint8Array(count * stride);
      MeshoptDecoder.decodeGltfBuffer(out, count, stride, bin, mode);
      assert.deepEqual(out, raw, `${name}: ${mode}, ${count} × ${stride} bytes`);
    }
    console.log(`# ${names.length} buffers decoded exactly`);
  });
}
