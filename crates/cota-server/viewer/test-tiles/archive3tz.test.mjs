// A `cota tiles --format 3dtiles -o OUT.3tz` archive read by loaders.gl's own
// 3D Tiles Archive reader (`@loaders.gl/3d-tiles` Tiles3DArchiveFileLoader:
// it finds `@3dtilesIndex1@` as the central directory's last entry and looks
// every path up by its MD5 in that index):
//  * every file of the directory pyramid made with the same options
//    (tileset.json, the subtrees, every GLB) comes back from the archive
//    byte for byte, and the archive holds nothing else;
//  * the index is the central directory's last entry, tileset.json its first.
// Environment: COTA_TILES3D_ARCHIVE (the .3tz) and COTA_TILES3D_ARCHIVE_DIR
// (the directory pyramid of the same tiles). Without them the test skips.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { Tiles3DArchiveFileLoader } from '@loaders.gl/3d-tiles';

const archive = process.env.COTA_TILES3D_ARCHIVE;
const dir = process.env.COTA_TILES3D_ARCHIVE_DIR;

/** Every file under `root` (names starting with a dot left out), as archive paths. */
function files(root, rel = '') {
  return fs.readdirSync(path.join(root, rel), { withFileTypes: true })
    .filter((e) => !e.name.startsWith('.'))
    .flatMap((e) => {
      const p = rel ? `${rel}/${e.name}` : e.name;
      return e.isDirectory() ? files(root, p) : [p];
    });
}

/** The central directory's file names, in order (no zip64 here: small archives). */
function centralNames(bytes) {
  const eocd = bytes.lastIndexOf(Buffer.from([0x50, 0x4b, 0x05, 0x06]));
  const count = bytes.readUInt16LE(eocd + 10);
  let at = bytes.readUInt32LE(eocd + 16);
  const names = [];
  for (let i = 0; i < count; i++) {
    const [n, m, k] = [bytes.readUInt16LE(at + 28), bytes.readUInt16LE(at + 30), bytes.readUInt16LE(at + 32)];
    names.push(bytes.subarray(at + 46, at + 46 + n).toString('utf8'));
    at += 46 + n + m + k;
  }
  return names;
}

if (!archive || !dir) {
  test('3D Tiles Archive in loaders.gl', { skip: 'set COTA_TILES3D_ARCHIVE and COTA_TILES3D_ARCHIVE_DIR (see .ci/run)' }, () => {});
} else {
  const bytes = fs.readFileSync(archive);
  const data = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
  const want = files(dir);

  test('loaders.gl reads every file of the pyramid from the .3tz, byte for byte', async () => {
    assert.ok(want.includes('tileset.json') && want.length > 100, `${want.length} files`);
    for (const p of want) {
      const got = await Tiles3DArchiveFileLoader.parse(data, { '3d-tiles-archive': { path: p } });
      assert.ok(Buffer.from(got).equals(fs.readFileSync(path.join(dir, p))), `${p} differs`);
    }
    await assert.rejects(Tiles3DArchiveFileLoader.parse(data, { '3d-tiles-archive': { path: 'no/such.glb' } }));
  });

  test('the index is the last entry, tileset.json the first, and the archive holds exactly the pyramid\'s files', () => {
    const names = centralNames(bytes);
    assert.equal(names.at(-1), '@3dtilesIndex1@');
    assert.deepEqual([...names.slice(0, -1)].sort(), [...want].sort());
    assert.equal(names[0], 'tileset.json');
  });
}
