// Turns one GF_VIEW.maps entry into a parsed map with what the first frame needs (its
// geometry, robust bounds and confidence range from a sample), or a message saying why there
// is nothing to draw (no surfels, unreadable data). Never throws.
import { base64ToBytes, parseSurfelPly, robustBounds, confidenceRange } from './ply.js';

// options.usePlyLoader: parse with PLYLoader even where the direct reader applies.
// mark(what): optional progress callback for timing (decoded, parsed).
// The result: { surfels (ply.js's rows, for countSources), geometry, count, bounds,
// confRange, message }.
export function loadMap(entry, options = {}, mark = () => {}) {
  const empty = { surfels: null, geometry: null, count: 0, bounds: null, confRange: null };
  if (!entry.ply_base64) return { ...empty, message: 'This map has no surfels.' };
  let parsed;
  try {
    const bytes = base64ToBytes(entry.ply_base64);
    mark('decoded');
    parsed = parseSurfelPly(bytes, options);
    mark(`parsed(${parsed.parser})`);
  } catch (err) {
    return { ...empty, message: `Could not read this map: ${err && err.message ? err.message : err}` };
  }
  const { surfels, geometry, count } = parsed;
  if (count === 0) return { ...empty, message: 'This map has no surfels.' };
  return {
    surfels,
    geometry,
    count,
    bounds: robustBounds(surfels),
    confRange: confidenceRange(surfels),
    message: '',
  };
}
