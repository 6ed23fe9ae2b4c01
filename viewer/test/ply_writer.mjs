// Writes surfel arrays (synth_scene.mjs's sampleScene) as a GlassFusion map.ply: binary
// little-endian, properties as in surfels/ply.h (35 bytes per vertex), or without the normals
// (23 bytes) as the reports' view_data.js carries a map (apps/map_view.cc).

const PROPS = [
  ['x', 'float'], ['y', 'float'], ['z', 'float'], ['nx', 'float'], ['ny', 'float'], ['nz', 'float'],
  ['red', 'uchar'], ['green', 'uchar'], ['blue', 'uchar'],
  ['radius', 'float'], ['confidence', 'float'], ['source', 'uchar'],
];

export function surfelPlyBytes(s, { normals = true } = {}) {
  const props = PROPS.filter(([name]) => normals || !name.startsWith('n'));
  const vertexBytes = props.reduce((n, [, type]) => n + (type === 'float' ? 4 : 1), 0);
  const header = ['ply', 'format binary_little_endian 1.0',
    'comment GlassFusion surfel map (world frame, metres)', `element vertex ${s.count}`,
    ...props.map(([name, type]) => `property ${type} ${name}`), 'end_header', ''].join('\n');
  const head = Buffer.from(header, 'ascii');
  const body = Buffer.alloc(s.count * vertexBytes);
  let o = 0;
  for (let i = 0; i < s.count; i++) {
    for (let k = 0; k < 3; k++, o += 4) body.writeFloatLE(s.pos[3 * i + k], o);
    if (normals) for (let k = 0; k < 3; k++, o += 4) body.writeFloatLE(s.nrm[3 * i + k], o);
    for (let k = 0; k < 3; k++, o += 1) body.writeUInt8(s.rgb[3 * i + k], o);
    body.writeFloatLE(s.radius[i], o); o += 4;
    body.writeFloatLE(s.conf[i], o); o += 4;
    body.writeUInt8(s.source[i], o); o += 1;
  }
  return Buffer.concat([head, body]);
}
