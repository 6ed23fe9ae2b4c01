// The viewer's page structure and style. Layout (the test relies on it):
//   .gf-toolbar   colour mode select, one checkbox per source, path/frusta checkbox
//   .gf-panes     the panes side by side; each a <figure> with a box <div data-pane="i"> (the
//                 pane's picture) and a <figcaption> naming the map and its surfel count;
//                 over them all one <canvas class="gf-canvas"> into which every pane is drawn
//                 at its box's place (pane.js; one WebGL context for all panes)
//   .gf-overlay   the clicked keyframe's label and fill overlay image

// Pane background (sRGB). The test reads it from each pane box's data-bg.
export const BACKGROUND = '#202124';

const STYLE = `
.gf-viewer { font: 14px/1.4 system-ui, sans-serif; color: #222; max-width: 1800px; }
.gf-toolbar { display: flex; flex-wrap: wrap; gap: 6px 18px; align-items: center; margin: 6px 0; }
.gf-toolbar label { white-space: nowrap; cursor: pointer; }
.gf-swatch { display: inline-block; width: 11px; height: 11px; border-radius: 50%;
  margin: 0 4px 0 2px; vertical-align: -1px; border: 1px solid #0004; }
.gf-ramp { display: inline-block; width: 90px; height: 10px; vertical-align: -1px; margin: 0 4px;
  background: linear-gradient(90deg, #450054, #3b528b, #21918c, #5ec962, #fde725); }
.gf-panes { position: relative; display: flex; gap: 8px; }
.gf-pane { flex: 1 1 0; min-width: 0; max-width: 900px; margin: 0; }
.gf-pane-box { position: relative; width: 100%; background: ${BACKGROUND}; }
.gf-surface { position: absolute; inset: 0; touch-action: none; }
.gf-canvas { position: absolute; left: 0; top: 0; width: 100%; height: 100%; z-index: 1;
  pointer-events: none; }
.gf-msg { position: absolute; inset: 0; display: flex; align-items: center; justify-content: center;
  color: #ddd; text-align: center; padding: 1em; pointer-events: none; z-index: 2; }
.gf-pane figcaption { padding: 3px 2px; }
.gf-pane figcaption b { margin-right: 6px; }
.gf-note { color: #555; }
.gf-hint { color: #666; font-size: 12px; margin: 4px 0; }
.gf-overlay { border-top: 1px solid #ccc; padding: 6px 0; }
.gf-overlay img { display: block; max-width: 100%; margin-top: 4px; image-rendering: auto; }
`;

// Adds the stylesheet once per document.
function addStyle(doc) {
  if (doc.getElementById('gf-viewer-style')) return;
  const style = doc.createElement('style');
  style.id = 'gf-viewer-style';
  style.textContent = STYLE;
  doc.head.appendChild(style);
}

// Creates an element with attributes/properties and children (strings become text).
export function el(tag, props = {}, children = []) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(props)) {
    if (key === 'className' || key === 'textContent' || key === 'checked' || key === 'value') node[key] = value;
    else node.setAttribute(key, value);
  }
  for (const child of children) node.append(child);
  return node;
}

// The caption under a pane: the map's name and how many surfels it shows.
function captionChildren(map) {
  const shown = map.surfels_shown;
  const total = map.surfels_total;
  const parts = [el('b', { textContent: map.name })];
  if (Number.isFinite(shown) && Number.isFinite(total) && shown < total) {
    parts.push(el('span', { className: 'gf-note',
      textContent: `showing ${fmt(shown)} of ${fmt(total)} surfels (the full map is in map.ply)` }));
  } else if (Number.isFinite(total)) {
    parts.push(el('span', { className: 'gf-note', textContent: `${fmt(total)} surfels` }));
  }
  return parts;
}

// 1234567 -> "1,234,567".
export function fmt(n) {
  return Math.round(n).toLocaleString('en-US');
}

// Builds the layout in `container` for `maps` (1 or 2). aspect: the sensor's width / height.
// Returns the elements the viewer fills in later: { container, toolbar, row (.gf-panes),
// canvas, panes: [{ box, surface, msg }], overlay }. A pane's surface (filling its box, under
// the canvas, which lets pointer events through) is what the mouse controls listen on.
export function buildLayout(container, maps, aspect) {
  addStyle(container.ownerDocument);
  container.classList.add('gf-viewer');
  container.textContent = '';
  const toolbar = el('div', { className: 'gf-toolbar' });
  const panesRow = el('div', { className: 'gf-panes' });
  const panes = maps.map((map, i) => {
    const surface = el('div', { className: 'gf-surface' });
    const msg = el('div', { className: 'gf-msg', textContent: 'loading…' });
    const box = el('div', { className: 'gf-pane-box', 'data-pane': String(i), 'data-map-name': map.name,
      'data-bg': BACKGROUND }, [surface, msg]);
    box.style.aspectRatio = String(aspect);
    const figure = el('figure', { className: 'gf-pane' }, [box, el('figcaption', {}, captionChildren(map))]);
    panesRow.append(figure);
    return { box, surface, msg };
  });
  const canvas = el('canvas', { className: 'gf-canvas' });
  panesRow.append(canvas);
  const hint = el('div', { className: 'gf-hint', textContent:
    'Drag to orbit, right-drag (or shift-drag) to pan, wheel to zoom; both panes share one camera. ' +
    'Click a keyframe frustum to see its fill overlay.' });
  const overlay = el('div', { className: 'gf-overlay' });
  container.append(toolbar, panesRow, hint, overlay);
  return { container, toolbar, row: panesRow, canvas, panes, overlay };
}

// Shows a message over a pane (or hides it for an empty string).
export function setPaneMessage(pane, text) {
  pane.msg.textContent = text;
  pane.msg.style.display = text ? '' : 'none';
}
