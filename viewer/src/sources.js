// The surfel sources of a GlassFusion map (the PLY's `uchar source`, DepthSource in
// surfels/surfel_map.h) with the label and colour the viewer shows for each.
// Colours are sRGB hex; the shader writes them to the canvas unchanged, so a pixel of a
// stereo-fill surfel in "source" colour mode is exactly #1b7837 (the test counts it).

export const SOURCES = [
  { id: 1, label: 'sensor', color: '#9e9e9e' },
  { id: 2, label: 'stereo fill', color: '#1b7837' },
  { id: 3, label: 'COLMAP fill', color: '#5aae61' },
  { id: 4, label: 'carried fill', color: '#a6dba0' },
  { id: 5, label: 'transparent (glass)', color: '#67a9cf' },
];

// Any other source number (0, 6, 7; larger ones are clamped to 7 in the shader).
export const OTHER_SOURCE_COLOR = '#e377c2';

// Highest source number with its own visibility bit and colour slot in the shader.
export const MAX_SOURCE_ID = 7;

// Label and colour of a source number, known or not.
export function sourceInfo(id) {
  const known = SOURCES.find((s) => s.id === id);
  if (known) return known;
  return { id, label: `source ${id}`, color: OTHER_SOURCE_COLOR };
}

// Colour slots 0..MAX_SOURCE_ID as [r, g, b] in 0..1 (sRGB), for the shader uniform.
export function sourceColorTable() {
  const table = [];
  for (let id = 0; id <= MAX_SOURCE_ID; id++) table.push(hexToRgb01(sourceInfo(id).color));
  return table;
}

// '#rrggbb' -> [r, g, b] with each channel in 0..1.
export function hexToRgb01(hex) {
  const v = parseInt(hex.slice(1), 16);
  return [((v >> 16) & 255) / 255, ((v >> 8) & 255) / 255, (v & 255) / 255];
}
