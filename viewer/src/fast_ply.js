// A direct reader for the common case of a binary little-endian PLY whose first element is
// `vertex` with scalar properties only (what GlassFusion's map.ply is). It does not copy or
// convert anything: the vertex rows stay as they are in the file and are uploaded to the GPU
// as they are, the shader reading each property's bytes at its offset in the row
// (surfel_material.js). Parsing a million surfels this way takes no time at all (PLYLoader,
// which builds one JavaScript object per vertex, takes ~2 s).
// Returns null for any other file; the caller then uses PLYLoader (ply.js).

// Byte sizes and PLY type names of the scalar types (with their aliases).
const TYPES = {
  char: [1, 'int8'], int8: [1, 'int8'], uchar: [1, 'uint8'], uint8: [1, 'uint8'],
  short: [2, 'int16'], int16: [2, 'int16'], ushort: [2, 'uint16'], uint16: [2, 'uint16'],
  int: [4, 'int32'], int32: [4, 'int32'], uint: [4, 'uint32'], uint32: [4, 'uint32'],
  float: [4, 'float32'], float32: [4, 'float32'], double: [8, 'float64'], float64: [8, 'float64'],
};
// The properties the viewer draws and the type each must have for the rows to be used as
// they are (anything else goes through PLYLoader).
const REQUIRED = {
  x: 'float32', y: 'float32', z: 'float32', red: 'uint8', green: 'uint8', blue: 'uint8',
  radius: 'float32', confidence: 'float32', source: 'uint8',
};
const MAX_HEADER_BYTES = 64 * 1024;

// The header's vertex layout: { count, stride, props: { name: { offset, type } }, bodyOffset }
// or null when the file (a Uint8Array) is not a binary little-endian PLY with a scalar vertex
// element.
export function readVertexLayout(bytes) {
  const text = new TextDecoder('latin1').decode(bytes.subarray(0, MAX_HEADER_BYTES));
  const end = text.indexOf('end_header\n');
  if (!text.startsWith('ply\n') || end < 0) return null;
  const lines = text.slice(0, end).split('\n').map((l) => l.trim().split(/\s+/));
  if (!lines.some((l) => l[0] === 'format' && l[1] === 'binary_little_endian')) return null;
  const elements = lines.filter((l) => l[0] === 'element');
  if (elements.length === 0 || elements[0][1] !== 'vertex') return null;
  const layout = { count: Number(elements[0][2]), stride: 0, props: {}, bodyOffset: end + 'end_header\n'.length };
  let inVertex = false;
  for (const l of lines) {
    if (l[0] === 'element') inVertex = l[1] === 'vertex';
    if (!inVertex || l[0] !== 'property') continue;
    const type = TYPES[l[1]];
    if (!type) return null;  // a list property (or an unknown type)
    layout.props[l[2]] = { offset: layout.stride, type: type[1] };
    layout.stride += type[0];
  }
  if (!Number.isInteger(layout.count) || layout.count < 0) return null;
  if (layout.bodyOffset + layout.count * layout.stride > bytes.byteLength) return null;
  return layout;
}

// The surfel rows of a PLY file (a Uint8Array) as the viewer draws them: { count, rows, stride, offsets } where
// rows is a Uint8Array view of the file's vertex data (no copy), stride the bytes per vertex
// and offsets the byte offset in a row of x, y, z, red (green and blue follow it), radius,
// confidence and source. Null when the rows cannot be used as they are (not a binary
// little-endian PLY, a property missing or of another type, green/blue not right after red).
export function readSurfelRows(bytes) {
  const layout = readVertexLayout(bytes);
  if (!layout) return null;
  const { props } = layout;
  for (const [name, type] of Object.entries(REQUIRED)) {
    if (!props[name] || props[name].type !== type) return null;
  }
  if (props.green.offset !== props.red.offset + 1 || props.blue.offset !== props.red.offset + 2) return null;
  const offsets = {};
  for (const name of ['x', 'y', 'z', 'red', 'radius', 'confidence', 'source']) offsets[name] = props[name].offset;
  const rows = bytes.subarray(layout.bodyOffset, layout.bodyOffset + layout.count * layout.stride);
  return { count: layout.count, rows, stride: layout.stride, offsets };
}
