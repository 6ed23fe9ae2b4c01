// Node unit tests of the PLY parsing (src/ply.js): the direct reader (the file's rows as they
// are) and PLYLoader (packed rows) must give identical surfels for GlassFusion map.ply files,
// and other PLYs must still load.
// Run: node --test viewer/test/
import test from 'node:test';
import assert from 'node:assert/strict';
import { parseSurfelPly, countSources, base64ToBytes, readSurfel } from '../src/ply.js';
import { readVertexLayout } from '../src/fast_ply.js';
import { sampleScene } from './synth_scene.mjs';
import { surfelPlyBytes } from './ply_writer.mjs';

// Every surfel of a parsed map, as readSurfel gives it.
function surfels(parsed) {
  const out = [];
  for (let i = 0; i < parsed.count; i++) out.push(readSurfel(parsed.surfels, i));
  return out;
}

for (const normals of [false, true]) {
  test(`direct reader and PLYLoader agree on a synthetic map (${normals ? 'with' : 'without'} normals)`, () => {
    const scene = sampleScene(3000, true, 5);
    const bytes = surfelPlyBytes(scene, { normals });
    const direct = parseSurfelPly(bytes);
    const loader = parseSurfelPly(bytes, { usePlyLoader: true });
    assert.equal(direct.parser, 'direct');
    assert.equal(loader.parser, 'PLYLoader');
    assert.equal(direct.count, scene.count);
    assert.deepEqual(surfels(direct), surfels(loader));
    const first = readSurfel(direct.surfels, 0);
    assert.equal(first.source, scene.source[0]);
    assert.deepEqual(first.rgb, scene.rgb.slice(0, 3));
    assert.equal(first.radius, Math.fround(scene.radius[0]));
    const counts = countSources(direct.surfels);
    for (let s = 1; s <= 5; s++) assert.equal(counts[s], scene.source.filter((v) => v === s).length);
  });
}

test('the geometry reads each property at its offset in the rows', () => {
  const scene = sampleScene(100, true, 7);
  const parsed = parseSurfelPly(surfelPlyBytes(scene, { normals: false }));
  const g = parsed.geometry;
  assert.equal(g.drawRange.count, parsed.count);
  const offsets = Object.fromEntries(Object.entries(g.attributes).map(([name, a]) => [name, [a.offset, a.itemSize]]));
  assert.deepEqual(offsets, {
    xBytes: [0, 4], yBytes: [4, 4], zBytes: [8, 4], rgbBytes: [12, 3], radiusBytes: [15, 4],
    confidenceBytes: [19, 4], sourceByte: [23, 1],
  });
  assert.equal(g.getAttribute('xBytes').data.stride, 24);
  assert.equal(g.getAttribute('xBytes').data.array.length, 24 * parsed.count);
});

test('an empty map parses to zero surfels on both paths', () => {
  const empty = { count: 0, pos: [], nrm: [], rgb: [], radius: [], conf: [], source: [] };
  const bytes = surfelPlyBytes(empty);
  assert.equal(parseSurfelPly(bytes).count, 0);
  assert.equal(parseSurfelPly(bytes, { usePlyLoader: true }).count, 0);
});

test('an ASCII PLY falls back to PLYLoader', () => {
  const text = ['ply', 'format ascii 1.0', 'element vertex 2', 'property float x', 'property float y',
    'property float z', 'property uchar red', 'property uchar green', 'property uchar blue',
    'property float radius', 'property float confidence', 'property uchar source', 'end_header',
    '0 0 1 10 20 30 0.01 5 1', '1 2 3 40 50 60 0.02 2 2', ''].join('\n');
  const bytes = new Uint8Array(Buffer.from(text));
  assert.equal(readVertexLayout(bytes), null);
  const parsed = parseSurfelPly(bytes);
  assert.equal(parsed.parser, 'PLYLoader');
  assert.deepEqual(surfels(parsed).map((s) => [...s.rgb, s.source]), [[10, 20, 30, 1], [40, 50, 60, 2]]);
  assert.deepEqual(readSurfel(parsed.surfels, 1).position, [1, 2, 3]);
  assert.equal(readSurfel(parsed.surfels, 1).confidence, 2);
});

test('a binary PLY with double positions goes through PLYLoader', () => {
  const header = ['ply', 'format binary_little_endian 1.0', 'element vertex 1', 'property double x',
    'property double y', 'property double z', 'property uchar red', 'property uchar green',
    'property uchar blue', 'property float radius', 'property float confidence', 'property uchar source',
    'end_header', ''].join('\n');
  const body = Buffer.alloc(36);
  [0.5, -1.25, 2].forEach((v, k) => body.writeDoubleLE(v, 8 * k));
  body.set([7, 8, 9], 24);
  body.writeFloatLE(0.01, 27);
  body.writeFloatLE(4, 31);
  body[35] = 3;
  const parsed = parseSurfelPly(new Uint8Array(Buffer.concat([Buffer.from(header), body])));
  assert.equal(parsed.parser, 'PLYLoader');
  const s = readSurfel(parsed.surfels, 0);
  assert.deepEqual([s.position, s.rgb, s.confidence, s.source], [[0.5, -1.25, 2], [7, 8, 9], 4, 3]);
});

test('a truncated binary PLY is not read past its end', () => {
  const bytes = surfelPlyBytes(sampleScene(100, true, 3));
  assert.equal(readVertexLayout(bytes.subarray(0, bytes.length - 10)), null);
});

test('base64 decoding round-trips, as one string and in chunks', () => {
  const data = Buffer.from([0, 1, 2, 250, 255, 128, 7]);
  const text = data.toString('base64');  // 12 characters
  assert.deepEqual(Array.from(base64ToBytes(text)), Array.from(data));
  assert.deepEqual(Array.from(base64ToBytes([text.slice(0, 8), text.slice(8)])), Array.from(data));
});
