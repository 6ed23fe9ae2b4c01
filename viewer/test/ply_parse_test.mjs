// Node unit tests of the PLY parsing (src/ply.js): the direct reader and PLYLoader must give
// identical attributes for GlassFusion map.ply files, and other PLYs must still load.
// Run: node --test viewer/test/
import test from 'node:test';
import assert from 'node:assert/strict';
import { parseSurfelPly, countSources, base64ToArrayBuffer } from '../src/ply.js';
import { readVertexLayout } from '../src/fast_ply.js';
import { sampleScene } from './synth_scene.mjs';
import { surfelPlyBytes } from './ply_writer.mjs';

const toArrayBuffer = (buf) => buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.length);

function attributes(parsed) {
  const a = (name) => Array.from(parsed.geometry.getAttribute(name).array);
  return { position: a('position'), srgbSource: a('srgbSource'), radiusConfidence: a('radiusConfidence') };
}

test('direct reader and PLYLoader agree on a synthetic map', () => {
  const scene = sampleScene(3000, true, 5);
  const buffer = toArrayBuffer(surfelPlyBytes(scene));
  const direct = parseSurfelPly(buffer);
  const loader = parseSurfelPly(buffer, { usePlyLoader: true });
  assert.equal(direct.parser, 'direct');
  assert.equal(loader.parser, 'PLYLoader');
  assert.equal(direct.count, scene.count);
  assert.deepEqual(attributes(direct), attributes(loader));
  assert.equal(direct.geometry.getAttribute('srgbSource').array[3], scene.source[0]);
  const counts = countSources(direct.geometry, direct.count);
  for (let s = 1; s <= 5; s++) assert.equal(counts[s], scene.source.filter((v) => v === s).length);
});

test('an empty map parses to zero surfels on both paths', () => {
  const empty = { count: 0, pos: [], nrm: [], rgb: [], radius: [], conf: [], source: [] };
  const buffer = toArrayBuffer(surfelPlyBytes(empty));
  assert.equal(parseSurfelPly(buffer).count, 0);
  assert.equal(parseSurfelPly(buffer, { usePlyLoader: true }).count, 0);
});

test('an ASCII PLY falls back to PLYLoader', () => {
  const text = ['ply', 'format ascii 1.0', 'element vertex 2', 'property float x', 'property float y',
    'property float z', 'property uchar red', 'property uchar green', 'property uchar blue',
    'property float radius', 'property float confidence', 'property uchar source', 'end_header',
    '0 0 1 10 20 30 0.01 5 1', '1 2 3 40 50 60 0.02 2 2', ''].join('\n');
  const buffer = toArrayBuffer(Buffer.from(text));
  assert.equal(readVertexLayout(buffer), null);
  const parsed = parseSurfelPly(buffer);
  assert.equal(parsed.parser, 'PLYLoader');
  assert.deepEqual(attributes(parsed).srgbSource, [10, 20, 30, 1, 40, 50, 60, 2]);
});

test('a truncated binary PLY is not read past its end', () => {
  const bytes = surfelPlyBytes(sampleScene(100, true, 3));
  assert.equal(readVertexLayout(toArrayBuffer(bytes.subarray(0, bytes.length - 10))), null);
});

test('base64 decoding round-trips', () => {
  const data = Buffer.from([0, 1, 2, 250, 255, 128, 7]);
  assert.deepEqual(Array.from(new Uint8Array(base64ToArrayBuffer(data.toString('base64')))), Array.from(data));
});
