// Decoding a map's base64 PLY (the page's GF_VIEW.maps[i].ply_base64) into a three.js
// geometry with the attributes the surfel shader reads, plus summary statistics.
import * as THREE from 'three';
import { PLYLoader } from 'three/examples/jsm/loaders/PLYLoader.js';
import { MAX_SOURCE_ID } from './sources.js';
import { readSurfelArrays } from './fast_ply.js';

// base64 text -> ArrayBuffer. Uses Uint8Array.fromBase64 where the browser has it (fast,
// no intermediate string), else atob.
export function base64ToArrayBuffer(text) {
  // One string, or chunks each a whole number of 4-character groups (a browser parses a script
  // of many short string literals about three times faster than one of a single huge literal).
  const chunks = Array.isArray(text) ? text : [text];
  const decoded = chunks.map(decodeChunk);
  const total = decoded.reduce((n, c) => n + c.length, 0);
  if (decoded.length === 1) return decoded[0].buffer;
  const bytes = new Uint8Array(total);
  let offset = 0;
  for (const c of decoded) {
    bytes.set(c, offset);
    offset += c.length;
  }
  return bytes.buffer;
}

function decodeChunk(text) {
  if (typeof Uint8Array.fromBase64 === 'function') return Uint8Array.fromBase64(text);
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
  return bytes;
}

// Parses a GlassFusion surfel PLY into a geometry with the attributes the shader reads:
//   position          float x3: x y z, world frame, metres
//   srgbSource        uchar x4: red green blue (0..255 sRGB, as stored) and source
//                     (DepthSource number, sources.js)
//   radiusConfidence  float x2: disc radius (metres) and confidence (accumulated weight)
// Packing four bytes and two floats per surfel keeps the attribute formats ones that every
// WebGL implementation takes as they are (3-byte vertex formats may be converted on upload).
// The GlassFusion layout is read directly (fast_ply.js); any other PLY goes through PLYLoader.
// options.usePlyLoader: always use PLYLoader (for comparison and tests).
export function parseSurfelPly(buffer, options = {}) {
  const direct = options.usePlyLoader ? null : readSurfelArrays(buffer);
  if (direct) return { geometry: geometryFromArrays(direct), count: direct.count, parser: 'direct' };
  const geometry = parseWithPlyLoader(buffer);
  const position = geometry.getAttribute('position');
  const count = position ? position.count : 0;
  if (count > 0) packAttributes(geometry, count);
  return { geometry, count, parser: 'PLYLoader' };
}

function geometryFromArrays({ position, srgbSource, radiusConfidence }) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(position, 3));
  geometry.setAttribute('srgbSource', new THREE.BufferAttribute(srgbSource, 4));
  geometry.setAttribute('radiusConfidence', new THREE.BufferAttribute(radiusConfidence, 2));
  return geometry;
}

// PLYLoader with the surfel properties as custom attributes (srgb, radius, confidence,
// source). The colour and normal properties are renamed before PLYLoader sees them, so that it
// skips its built-in `color` (converted to linear and re-quantised to 8 bits, which loses dark
// shades) and `normal` attributes: the shader uses neither, and skipping them makes parsing a
// million surfels about 40% faster. The colour comes through the custom `srgb` attribute.
function parseWithPlyLoader(buffer) {
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
  return loader.parse(buffer);
}

// Replaces PLYLoader's srgb, source, radius and confidence attributes by the packed
// srgbSource and radiusConfidence.
function packAttributes(geometry, count) {
  const get = (name) => {
    const attr = geometry.getAttribute(name);
    if (!attr) throw new Error(`the PLY has no vertex property for "${name}"`);
    return attr.array;
  };
  const [rgb, src, radius, conf] = ['srgb', 'source', 'radius', 'confidence'].map(get);
  const bytes = new Uint8Array(4 * count);
  const floats = new Float32Array(2 * count);
  for (let i = 0; i < count; i++) {
    bytes[4 * i] = rgb[3 * i];
    bytes[4 * i + 1] = rgb[3 * i + 1];
    bytes[4 * i + 2] = rgb[3 * i + 2];
    bytes[4 * i + 3] = src[i];
    floats[2 * i] = radius[i];
    floats[2 * i + 1] = conf[i];
  }
  for (const name of ['srgb', 'source', 'radius', 'confidence']) geometry.deleteAttribute(name);
  geometry.setAttribute('srgbSource', new THREE.BufferAttribute(bytes, 4));
  geometry.setAttribute('radiusConfidence', new THREE.BufferAttribute(floats, 2));
}

// Per-source surfel counts: array indexed by source number 0..MAX_SOURCE_ID (larger
// numbers are counted in the last slot, as the shader clamps them).
export function countSources(geometry, count) {
  const counts = new Array(MAX_SOURCE_ID + 1).fill(0);
  if (count === 0) return counts;
  const bytes = geometry.getAttribute('srgbSource').array;
  for (let i = 0; i < count; i++) counts[Math.min(bytes[4 * i + 3], MAX_SOURCE_ID)]++;
  return counts;
}

// Robust extent of the map: per-axis 1st and 99th percentiles of up to `samples` positions,
// so that a few stray surfels do not shrink the initial view. Returns null for an empty map.
export function robustBounds(geometry, count, samples = 20000) {
  if (count === 0) return null;
  const pos = geometry.getAttribute('position').array;
  const step = Math.max(1, Math.floor(count / samples));
  const axes = [[], [], []];
  for (let i = 0; i < count; i += step) {
    for (let a = 0; a < 3; a++) axes[a].push(pos[3 * i + a]);
  }
  const lo = [];
  const hi = [];
  for (const values of axes) {
    values.sort((p, q) => p - q);
    lo.push(percentile(values, 0.01));
    hi.push(percentile(values, 0.99));
  }
  return { min: lo, max: hi };
}

// Range of confidence used for the colour ramp: 0 to the 98th percentile of a sample.
export function confidenceRange(geometry, count, samples = 20000) {
  if (count === 0) return null;
  const floats = geometry.getAttribute('radiusConfidence').array;
  const step = Math.max(1, Math.floor(count / samples));
  const values = [];
  for (let i = 0; i < count; i += step) values.push(floats[2 * i + 1]);
  values.sort((p, q) => p - q);
  return [Math.min(0, values[0]), Math.max(percentile(values, 0.98), 1e-6)];
}

// Value at fraction q (0..1) of sorted values.
function percentile(sorted, q) {
  return sorted[Math.min(sorted.length - 1, Math.floor(q * sorted.length))];
}
