// Decoding a map's base64 PLY (the page's GF_VIEW.maps[i].ply_base64) into "surfel rows" and
// a three.js geometry over them, plus summary statistics.
//
// Surfel rows: { count, rows, stride, offsets } — rows is a Uint8Array of count * stride bytes,
// one row per surfel, and offsets gives the byte offset in a row of
//   x, y, z      float32 (little-endian): position, world frame, metres
//   red          uint8 x3 (red, green, blue follow each other): colour, 0..255 sRGB as stored
//   radius       float32: disc radius, metres
//   confidence   float32: accumulated measurement weight
//   source       uint8: DepthSource number (sources.js)
// GlassFusion's PLY rows are used as they are (fast_ply.js); any other PLY is read with
// three's PLYLoader and packed into rows of that kind.
import * as THREE from 'three';
import { PLYLoader } from 'three/examples/jsm/loaders/PLYLoader.js';
import { MAX_SOURCE_ID } from './sources.js';
import { readSurfelRows } from './fast_ply.js';

// base64 text -> Uint8Array: one string, or chunks each a whole number of 4-character groups
// (a browser parses a script of many short string literals about three times faster than one
// of a single huge literal). Decodes straight into one array with Uint8Array.setFromBase64
// where the browser has it (about twice as fast as decoding chunks and joining them).
export function base64ToBytes(text) {
  const chunks = Array.isArray(text) ? text : [text];
  if (typeof Uint8Array.prototype.setFromBase64 === 'function') {
    const capacity = chunks.reduce((n, c) => n + Math.ceil(c.length / 4) * 3, 0);
    const bytes = new Uint8Array(capacity);
    let written = 0;
    for (const c of chunks) written += bytes.subarray(written).setFromBase64(c).written;
    return bytes.subarray(0, written);
  }
  const decoded = chunks.map(decodeWithAtob);
  if (decoded.length === 1) return decoded[0];
  const bytes = new Uint8Array(decoded.reduce((n, c) => n + c.length, 0));
  let offset = 0;
  for (const c of decoded) {
    bytes.set(c, offset);
    offset += c.length;
  }
  return bytes;
}

function decodeWithAtob(text) {
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
  return bytes;
}

// Parses a surfel PLY (a Uint8Array of the file) into { surfels (rows as above), geometry,
// count, parser }. options.usePlyLoader: always use PLYLoader (for comparison and tests).
export function parseSurfelPly(bytes, options = {}) {
  let surfels = options.usePlyLoader ? null : readSurfelRows(bytes);
  const parser = surfels ? 'direct' : 'PLYLoader';
  if (!surfels) surfels = rowsFromPlyLoader(parseWithPlyLoader(bytes));
  return { surfels, geometry: surfelGeometry(surfels), count: surfels.count, parser };
}

// The geometry the surfel shader draws: the rows uploaded as they are, one vertex per row, and
// each property's bytes as an attribute at its offset (unsigned bytes, not normalised; the
// shader puts the bytes of a float back together). The geometry has no `position` attribute,
// so its draw range says how many vertices to draw.
export function surfelGeometry({ count, rows, stride, offsets }) {
  const geometry = new THREE.BufferGeometry();
  if (count === 0) return geometry;
  const data = new THREE.InterleavedBuffer(rows, stride);
  const add = (name, size, offset) => geometry.setAttribute(name, new THREE.InterleavedBufferAttribute(data, size, offset));
  add('xBytes', 4, offsets.x);
  add('yBytes', 4, offsets.y);
  add('zBytes', 4, offsets.z);
  add('rgbBytes', 3, offsets.red);
  add('radiusBytes', 4, offsets.radius);
  add('confidenceBytes', 4, offsets.confidence);
  add('sourceByte', 1, offsets.source);
  geometry.setDrawRange(0, count);
  return geometry;
}

// PLYLoader with the surfel properties as custom attributes (srgb, radius, confidence,
// source). The colour and normal properties are renamed before PLYLoader sees them, so that it
// skips its built-in `color` (converted to linear and re-quantised to 8 bits, which loses dark
// shades) and `normal` attributes: the shader uses neither, and skipping them makes parsing a
// million surfels about 40% faster. The colour comes through the custom `srgb` attribute.
function parseWithPlyLoader(bytes) {
  const loader = new PLYLoader();
  loader.setPropertyNameMapping({
    red: 'gf_red', green: 'gf_green', blue: 'gf_blue', nx: 'gf_nx', ny: 'gf_ny', nz: 'gf_nz',
  });
  loader.setCustomPropertyNameMapping({
    srgb: ['gf_red', 'gf_green', 'gf_blue'],
    radius: ['radius'],
    confidence: ['confidence'],
    source: ['source'],
  });
  return loader.parse(new Uint8Array(bytes).buffer);  // a copy: an ArrayBuffer of exactly the file
}

// Rows of 24 bytes (x y z, red green blue source, radius confidence: floats aligned) from
// PLYLoader's position, srgb, source, radius and confidence attributes.
const PACKED = { stride: 24, offsets: { x: 0, y: 4, z: 8, red: 12, source: 15, radius: 16, confidence: 20 } };

function rowsFromPlyLoader(geometry) {
  const position = geometry.getAttribute('position');
  const count = position ? position.count : 0;
  const rows = new Uint8Array(PACKED.stride * count);
  if (count === 0) return { count, rows, ...PACKED };
  const get = (name) => {
    const attr = geometry.getAttribute(name);
    if (!attr) throw new Error(`the PLY has no vertex property for "${name}"`);
    return attr.array;
  };
  const [pos, rgb, src, radius, conf] = ['position', 'srgb', 'source', 'radius', 'confidence'].map(get);
  const floats = new Float32Array(rows.buffer);  // 6 per row
  for (let i = 0; i < count; i++) {
    for (let k = 0; k < 3; k++) {
      floats[6 * i + k] = pos[3 * i + k];
      rows[24 * i + 12 + k] = rgb[3 * i + k];
    }
    rows[24 * i + 15] = src[i];
    floats[6 * i + 4] = radius[i];
    floats[6 * i + 5] = conf[i];
  }
  return { count, rows, ...PACKED };
}

// Reads surfel i of the rows: { position: [x, y, z], rgb: [r, g, b], radius, confidence, source }.
export function readSurfel({ rows, stride, offsets }, i) {
  const view = new DataView(rows.buffer, rows.byteOffset, rows.byteLength);
  const at = i * stride;
  const float = (name) => view.getFloat32(at + offsets[name], true);
  return {
    position: [float('x'), float('y'), float('z')],
    rgb: Array.from(rows.subarray(at + offsets.red, at + offsets.red + 3)),
    radius: float('radius'),
    confidence: float('confidence'),
    source: rows[at + offsets.source],
  };
}

// Per-source surfel counts: array indexed by source number 0..MAX_SOURCE_ID (larger
// numbers are counted in the last slot, as the shader clamps them).
export function countSources({ count, rows, stride, offsets }) {
  const counts = new Array(MAX_SOURCE_ID + 1).fill(0);
  for (let i = 0, at = offsets.source; i < count; i++, at += stride) counts[Math.min(rows[at], MAX_SOURCE_ID)]++;
  return counts;
}

// Float property `name` of up to `samples` surfels spread evenly over the rows, sorted.
function sampleSorted({ count, rows, stride, offsets }, name, samples) {
  const view = new DataView(rows.buffer, rows.byteOffset, rows.byteLength);
  const step = Math.max(1, Math.floor(count / samples));
  const values = new Float32Array(Math.ceil(count / step));
  for (let i = 0, k = 0; i < count; i += step, k++) values[k] = view.getFloat32(i * stride + offsets[name], true);
  return values.sort();
}

// Robust extent of the map: per-axis 1st and 99th percentiles of up to `samples` positions,
// so that a few stray surfels do not shrink the initial view. Returns null for an empty map.
export function robustBounds(surfels, samples = 20000) {
  if (surfels.count === 0) return null;
  const lo = [];
  const hi = [];
  for (const axis of ['x', 'y', 'z']) {
    const values = sampleSorted(surfels, axis, samples);
    lo.push(percentile(values, 0.01));
    hi.push(percentile(values, 0.99));
  }
  return { min: lo, max: hi };
}

// Range of confidence used for the colour ramp: 0 to the 98th percentile of a sample.
export function confidenceRange(surfels, samples = 20000) {
  if (surfels.count === 0) return null;
  const values = sampleSorted(surfels, 'confidence', samples);
  return [Math.min(0, values[0]), Math.max(percentile(values, 0.98), 1e-6)];
}

// Value at fraction q (0..1) of sorted values.
function percentile(sorted, q) {
  return sorted[Math.min(sorted.length - 1, Math.floor(q * sorted.length))];
}
