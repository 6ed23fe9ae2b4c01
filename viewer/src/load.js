// Turns one GF_VIEW.maps entry into a parsed map with its statistics, or a message saying
// why there is nothing to draw (no surfels, unreadable data). Never throws.
import { base64ToArrayBuffer, parseSurfelPly, countSources, robustBounds, confidenceRange } from './ply.js';
import { MAX_SOURCE_ID } from './sources.js';

// options.usePlyLoader: parse with PLYLoader even where the direct reader applies.
// mark(what): optional progress callback for timing (decoded, parsed).
export function loadMap(entry, options = {}, mark = () => {}) {
  const empty = { geometry: null, count: 0, bounds: null, confRange: null,
    sourceCounts: new Array(MAX_SOURCE_ID + 1).fill(0) };
  if (!entry.ply_base64) return { ...empty, message: 'This map has no surfels.' };
  let parsed;
  try {
    const buffer = base64ToArrayBuffer(entry.ply_base64);
    mark('decoded');
    parsed = parseSurfelPly(buffer, options);
    mark(`parsed(${parsed.parser})`);
  } catch (err) {
    return { ...empty, message: `Could not read this map: ${err && err.message ? err.message : err}` };
  }
  const { geometry, count } = parsed;
  if (count === 0) return { ...empty, message: 'This map has no surfels.' };
  return {
    geometry,
    count,
    bounds: robustBounds(geometry, count),
    confRange: confidenceRange(geometry, count),
    sourceCounts: countSources(geometry, count),
    message: '',
  };
}
