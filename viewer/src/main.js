// GlassFusion report viewer: the surfel maps of a run side by side (e.g. "with fill" and
// "without fill") under one shared camera. Bundled as the global GFViewer; a report calls
//   GFViewer.mount(document.getElementById('gf-view'), window.GF_VIEW);
// Test hooks: documentElement.dataset.view = "ready" once every pane has drawn its first
// frame, dataset.viewMs = milliseconds from mount() to then, dataset.pageMs = milliseconds from
// opening the page to then (reading view_data.js included), and dataset.viewSteps = when
// each step ended (WebGL context created, map decoded, parsed, drawing submitted, drawn), in ms.
import { buildLayout, setPaneMessage } from './dom.js';
import { buildToolbar, buildOverlayPanel } from './controls_ui.js';
import { loadMap } from './load.js';
import {
  createRenderer, compileShaders, createPane, resizeRenderer, renderPane, clearCanvas, setPaneUniform, waitForDrawing,
} from './pane.js';
import { countSources } from './ply.js';
import { frustumDepth, poseToMatrix } from './scene_extras.js';
import { intrinsicsFrom, createViewCamera, sceneSphere, placeInitialView } from './view_camera.js';
import { attachSharedControls } from './interaction.js';
import { COLOR_MODES } from './surfel_material.js';
import { MAX_SOURCE_ID } from './sources.js';
import * as THREE from 'three';

// Lets the browser paint (e.g. the "loading…" messages) before the next heavy step.
const nextTask = () => new Promise((resolve) => setTimeout(resolve, 0));

// The page's data with defaults for whatever is missing.
function normalizeView(data) {
  const view = data || {};
  const maps = (Array.isArray(view.maps) ? view.maps : []).slice(0, 2).map((m, i) => ({
    name: String(m && m.name != null ? m.name : `map ${i + 1}`),
    ply_base64: (m && m.ply_base64) || '',
    surfels_total: Number(m && m.surfels_total),
    surfels_shown: Number(m && m.surfels_shown),
  }));
  const keyframes = (Array.isArray(view.keyframes) ? view.keyframes : [])
    .filter((k) => k && typeof k === 'object')
    .map((k) => ({ label: String(k.label ?? ''), overlay: k.overlay || '', matrix: poseToMatrix(k.world_from_camera) }))
    .filter((k) => k.matrix);
  const trajectory = Array.isArray(view.trajectory) ? view.trajectory : [];
  return { maps, keyframes, trajectory, intr: intrinsicsFrom(view.camera) };
}

// Mounts the viewer into `container`. Returns a promise that resolves when the first frames
// are drawn (the page does not need to wait for it). options.parser = 'plyloader' (or
// "#gf-parser=plyloader" in the page's URL) parses every map with three's PLYLoader instead of
// the direct reader, to compare the two.
export function mount(container, data, options = {}) {
  const t0 = performance.now();
  const root = document.documentElement;
  delete root.dataset.view;
  const view = normalizeView(data);
  view.usePlyLoader = options.parser === 'plyloader' || /gf-parser=plyloader/.test(location.hash);
  const layout = buildLayout(container, view.maps, view.intr.width / view.intr.height);
  if (view.maps.length === 0) {
    layout.overlay.textContent = 'This report has no surfel maps to show.';
    root.dataset.view = 'ready';
    root.dataset.viewMs = String(Math.round(performance.now() - t0));
    return Promise.resolve();
  }
  return start(view, layout, t0).catch((err) => {
    // E.g. no WebGL 2: say so on the page instead of leaving "loading…".
    console.error(err);
    layout.overlay.textContent = `The 3D view failed: ${err && err.message ? err.message : err}`;
    layout.panes.forEach((p) => setPaneMessage(p, 'The 3D view is not available.'));
    root.dataset.view = 'error';
  });
}

// Parses the maps one by one and draws each pane as soon as its map is parsed, so that the
// GPU (a separate process) draws one pane while the next map is being parsed. Then adds the
// controls and waits for the first frames to finish.
async function start(view, layout, t0) {
  const steps = [];  // "what ms" marks since mount(), for dataset.viewSteps
  const mark = (what) => steps.push(`${what} ${Math.round(performance.now() - t0)}`);
  const camera = createViewCamera(view.intr);
  const renderer = createRenderer(layout.canvas);
  const redraw = makeRedraw(renderer, layout, camera);
  redraw.resize();
  compileShaders(renderer, camera);
  mark('context');
  const maps = [];
  const panes = [];
  let frame = null;  // { target, depth } once the view is placed
  for (let i = 0; i < view.maps.length; i++) {
    await nextTask();
    maps.push(loadMap(view.maps[i], { usePlyLoader: view.usePlyLoader }, (what) => mark(`${what}${i}`)));
    setPaneMessage(layout.panes[i], maps[i].message);
    layout.panes[i].box.dataset.surfels = String(maps[i].count);
    // Frame the view on the first map with surfels (with the path and keyframes).
    if (!frame && (maps[i].bounds || i === view.maps.length - 1)) frame = frameView(camera, view, maps[i]);
    while (frame && panes.length < maps.length) {
      const j = panes.length;
      const extras = { trajectory: view.trajectory, keyframes: view.keyframes, camera: view.intr, depth: frame.depth };
      panes.push(createPane(layout.panes[j], maps[j], maps[j].confRange || [0, 1], extras, renderer.maxPointPx));
      renderPane(renderer, panes[j], camera);
      mark(`submitted${j}`);
    }
  }
  redraw.setPanes(panes);
  const confRange = mergeRanges(maps.map((m) => m.confRange));
  if (confRange) panes.forEach((p) => setPaneUniform(p, 'uConfRange', new THREE.Vector2(...confRange)));
  addInteraction(view, layout, { maps, panes, camera, frame, confRange, redraw });
  layout.container.gfView = testHandle(view, panes, camera, frame);
  waitForDrawing(renderer);
  mark('drawn');
  const root = document.documentElement;
  root.dataset.viewSteps = steps.join(', ');
  root.dataset.viewMs = String(Math.round(performance.now() - t0));
  root.dataset.pageMs = String(Math.round(performance.now()));  // since the page was opened
  root.dataset.view = 'ready';
  observeResize(layout, redraw);
}

// Places the shared camera to frame `map` (may be empty) with the path and keyframes.
// Returns the orbit target and the keyframe frustum depth (metres).
function frameView(camera, view, map) {
  const points = view.keyframes.map((k) => new THREE.Vector3().setFromMatrixPosition(k.matrix));
  for (const p of view.trajectory) if (Array.isArray(p) && p.every(Number.isFinite)) points.push(new THREE.Vector3(...p));
  const sphere = sceneSphere([map.bounds], points);
  const target = placeInitialView(camera, sphere, view.keyframes.length ? view.keyframes[0].matrix : null);
  return { target, depth: frustumDepth(sphere.radius, view.keyframes) };
}

// The toolbar, the overlay panel and the mouse controls.
function addInteraction(view, layout, { maps, panes, camera, frame, confRange, redraw }) {
  const showOverlay = buildOverlayPanel(layout.overlay, view.keyframes.length);
  buildToolbar(layout.toolbar, {
    sourceCounts: sumCounts(maps.filter((m) => m.surfels).map((m) => countSources(m.surfels))),
    confRange,
    hasPath: view.trajectory.length >= 2 || view.keyframes.length > 0,
  }, toolbarHandlers(panes, redraw));
  attachSharedControls({
    panes, camera, target: frame.target, keyframes: view.keyframes, depth: frame.depth,
    onChange: redraw.request,
    onPick: (index) => {
      panes.forEach((p) => p.overlay.setSelected(index));
      showOverlay(view.keyframes[index]);
      redraw.request();
    },
  });
}

// A small handle on the container (container.gfView) for tests: where keyframe `index`'s
// frustum centre is on screen in pane `pane`, as page (client) pixel coordinates.
function testHandle(view, panes, camera, frame) {
  return {
    keyframeClientPoint(index, pane) {
      const p = new THREE.Vector3(0, 0, frame.depth / 2).applyMatrix4(view.keyframes[index].matrix).project(camera);
      const rect = panes[pane].layoutPane.box.getBoundingClientRect();
      return { x: rect.left + ((p.x + 1) / 2) * rect.width, y: rect.top + ((1 - p.y) / 2) * rect.height };
    },
  };
}

// Redraw scheduling: request() draws all panes on the next animation frame (once however
// often it is called); resize() matches the canvas to its box and the camera's aspect to the
// panes' (all panes are the same size). changed(): whether the canvas or a pane box has
// changed size since the last resize().
function makeRedraw(renderer, layout, camera) {
  let panes = [];
  let pending = false;
  let size = '';
  const sizeNow = () => [layout.canvas, ...layout.panes.map((p) => p.box)]
    .map((e) => `${e.clientWidth}x${e.clientHeight}`).join(' ');
  const draw = () => {
    pending = false;
    clearCanvas(renderer);
    panes.forEach((p) => renderPane(renderer, p, camera));
  };
  return {
    setPanes(list) { panes = list; },
    request() { if (!pending) { pending = true; requestAnimationFrame(draw); } },
    changed: () => sizeNow() !== size,
    resize() {
      size = sizeNow();
      resizeRenderer(renderer);
      const box = layout.panes[0].box;
      camera.aspect = Math.max(1, box.clientWidth) / Math.max(1, box.clientHeight);
      camera.updateProjectionMatrix();
    },
  };
}

// Resizes and redraws when the canvas or a pane's box changes size (window resize, a
// scrollbar appearing, a collapsed report section opened).
function observeResize(layout, redraw) {
  if (typeof ResizeObserver === 'undefined') return;
  const observer = new ResizeObserver(() => {
    if (!redraw.changed()) return;
    redraw.resize();
    redraw.request();
  });
  [layout.canvas, ...layout.panes.map((p) => p.box)].forEach((e) => observer.observe(e));
}

// The toolbar's effects on the panes.
function toolbarHandlers(panes, redraw) {
  return {
    onColorMode(name) {
      panes.forEach((p) => setPaneUniform(p, 'uColorMode', COLOR_MODES[name] ?? 0));
      redraw.request();
    },
    onSourceMask(mask) {
      panes.forEach((p) => setPaneUniform(p, 'uSourceMask', mask));
      redraw.request();
    },
    onPath(visible) {
      panes.forEach((p) => { p.overlay.group.visible = visible; });
      redraw.request();
    },
  };
}

// Element-wise sum of per-source count arrays.
function sumCounts(lists) {
  const sum = new Array(MAX_SOURCE_ID + 1).fill(0);
  for (const list of lists) list.forEach((n, i) => { sum[i] += n; });
  return sum;
}

// One confidence range for all panes, so equal colours mean equal confidence.
function mergeRanges(ranges) {
  const valid = ranges.filter(Boolean);
  if (valid.length === 0) return null;
  return [Math.min(...valid.map((r) => r[0])), Math.max(...valid.map((r) => r[1]))];
}
