// The toolbar controls and the keyframe overlay panel. Control ids are stable (the test uses
// them): gf-color-mode, gf-source-<n>, gf-path.
import { el, fmt } from './dom.js';
import { sourceInfo } from './sources.js';

// Fills the toolbar. sourceCounts: surfels per source number, summed over the maps.
// confRange: [lo, hi] of the confidence ramp, or null. hasPath: any path or keyframe.
// handlers: { onColorMode(name), onSourceMask(mask), onPath(visible) }.
export function buildToolbar(toolbar, { sourceCounts, confRange, hasPath }, handlers) {
  const select = el('select', { id: 'gf-color-mode' }, [
    el('option', { value: 'rgb', textContent: 'surfel colour' }),
    el('option', { value: 'source', textContent: 'source' }),
    el('option', { value: 'confidence', textContent: 'confidence' }),
  ]);
  const legend = el('span', { className: 'gf-note' });
  if (confRange) {
    legend.append(`confidence ${round2(confRange[0])}`, el('span', { className: 'gf-ramp' }), `≥ ${round2(confRange[1])}`);
  }
  legend.style.display = 'none';
  select.addEventListener('change', () => {
    legend.style.display = select.value === 'confidence' ? '' : 'none';
    handlers.onColorMode(select.value);
  });
  toolbar.append(el('label', {}, ['Colour: ', select]), legend);

  const boxes = [];
  sourceCounts.forEach((count, id) => {
    if (count === 0) return;
    const info = sourceInfo(id);
    const box = el('input', { type: 'checkbox', id: `gf-source-${id}`, checked: true, 'data-source': String(id) });
    const swatch = el('span', { className: 'gf-swatch' });
    swatch.style.background = info.color;
    box.addEventListener('change', () => handlers.onSourceMask(sourceMask(boxes)));
    boxes.push(box);
    toolbar.append(el('label', { title: `${fmt(count)} surfels` }, [box, swatch, info.label]));
  });

  const path = el('input', { type: 'checkbox', id: 'gf-path', checked: hasPath });
  if (!hasPath) path.disabled = true;
  path.addEventListener('change', () => handlers.onPath(path.checked));
  toolbar.append(el('label', {}, [path, ' camera path & keyframes']));
}

// Bitmask of visible sources: all bits set except the unchecked sources'.
function sourceMask(boxes) {
  let mask = 0xff;
  for (const box of boxes) {
    if (!box.checked) mask &= ~(1 << Number(box.dataset.source));
  }
  return mask;
}

function round2(x) {
  return Math.round(x * 100) / 100;
}

// The panel under the panes. Returns show(keyframe) for a clicked keyframe.
export function buildOverlayPanel(panel, keyframeCount) {
  const title = el('div');
  const body = el('div', { className: 'gf-note' });
  panel.append(title, body);
  title.textContent = keyframeCount > 0
    ? 'Click a keyframe frustum (red) to show its fill overlay here.'
    : 'This run has no keyframes.';
  return function show(kf) {
    title.textContent = '';
    title.append(el('b', { textContent: `Keyframe ${kf.label}` }));
    body.textContent = '';
    if (!kf.overlay) {
      body.textContent = 'No fill overlay for this keyframe.';
      return;
    }
    const img = el('img', { alt: `fill overlay of keyframe ${kf.label}`, src: kf.overlay });
    img.addEventListener('error', () => { body.textContent = `Overlay image not found: ${kf.overlay}`; });
    body.append(kf.overlay, img);
  };
}
