// The panes and the one WebGLRenderer that draws them all. Its canvas lies over the whole row
// of panes (dom.js); each pane's scene (the map's surfels, the camera path and frusta) is drawn
// into the part of the canvas over the pane's box (viewport and scissor), with the shared
// camera. One WebGL context instead of one per pane: the surfel shader compiles once, and no
// second context has to be created (which waits for the first context's drawing to finish).
import * as THREE from 'three';
import { BACKGROUND } from './dom.js';
import { createSurfelMaterial } from './surfel_material.js';
import { buildPathAndFrusta } from './scene_extras.js';

const BACKGROUND_COLOR = new THREE.Color(BACKGROUND);

// The renderer on layout.canvas. Its canvas is transparent outside the panes (the captions
// under the boxes show through). maxPointPx: the hardware's largest point size.
export function createRenderer(canvas) {
  // Sized before the context is made, so that its drawing buffer is not made twice.
  const ratio = window.devicePixelRatio || 1;
  canvas.width = Math.floor(Math.max(1, canvas.clientWidth) * ratio);
  canvas.height = Math.floor(Math.max(1, canvas.clientHeight) * ratio);
  const renderer = new THREE.WebGLRenderer({
    canvas,
    alpha: true,
    antialias: false,             // MSAA would cost 4x the fill in software rendering
    preserveDrawingBuffer: true,  // panes are drawn one at a time; lets the test read them back
    powerPreference: 'high-performance',
  });
  renderer.setPixelRatio(ratio);
  renderer.autoClear = false;     // each pane clears its own part (renderPane)
  const gl = renderer.getContext();
  renderer.maxPointPx = gl.getParameter(gl.ALIASED_POINT_SIZE_RANGE)[1];
  return renderer;
}

// Has the panes' shaders (surfels, lines) compiled by the GPU process while the first map is
// decoded. (three checks a new shader on first use and waits for it; see createPane for why
// the path and frusta are drawn first.)
export function compileShaders(renderer, camera) {
  const material = createSurfelMaterial({ maxPointPx: renderer.maxPointPx, confRange: [0, 1] });
  const scene = new THREE.Scene();
  scene.add(new THREE.Points(new THREE.BufferGeometry(), material));
  // (The line needs a `position` attribute like the real ones: it is part of three's shader key.)
  const line = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3(0, 0, 1)]);
  scene.add(new THREE.Line(line, new THREE.LineBasicMaterial()));
  renderer.compile(scene, camera);
  renderer.getContext().flush();  // sends the compile commands to the GPU process now
}

// Creates a pane's scene. layoutPane: from dom.buildLayout; map: the parsed map ({ geometry,
// count } or null); extras: arguments for buildPathAndFrusta.
export function createPane(layoutPane, map, confRange, extras, maxPointPx) {
  layoutPane.box.dataset.maxPointPx = String(maxPointPx);
  const scene = new THREE.Scene();
  let material = null;
  if (map && map.count > 0) {
    material = createSurfelMaterial({ maxPointPx, confRange });
    const points = new THREE.Points(map.geometry, material);
    points.frustumCulled = false;  // the bounding sphere is not needed (nor computable: no `position`)
    // Drawn after the path and frusta: three checks each new shader on first use, which waits
    // for the GPU process to finish everything before it, and drawing the surfels takes long.
    points.renderOrder = 1;
    scene.add(points);
  }
  const overlay = buildPathAndFrusta(extras);
  scene.add(overlay.group);
  return { layoutPane, scene, material, overlay };
}

// Matches the drawing buffer to the canvas's CSS size (times the device pixel ratio), which
// clears it.
export function resizeRenderer(renderer) {
  const canvas = renderer.domElement;
  renderer.setSize(Math.max(1, canvas.clientWidth), Math.max(1, canvas.clientHeight), false);
}

// The pane's box in drawing buffer pixels, { x, y, width, height } from the canvas's top left:
// the box's edges rounded to whole pixels (the test reads the same pixels back).
function paneRect(renderer, pane) {
  const canvas = renderer.domElement.getBoundingClientRect();
  const box = pane.layoutPane.box.getBoundingClientRect();
  const sx = renderer.domElement.width / Math.max(1, canvas.width);
  const sy = renderer.domElement.height / Math.max(1, canvas.height);
  const x = Math.round((box.left - canvas.left) * sx);
  const y = Math.round((box.top - canvas.top) * sy);
  const width = Math.max(1, Math.round((box.right - canvas.left) * sx) - x);
  const height = Math.max(1, Math.round((box.bottom - canvas.top) * sy) - y);
  return { x, y, width, height };
}

// Draws the pane into its part of the canvas and hands the commands to the GPU without
// waiting for them. The disc size scale matches the pane: focal (drawing buffer px) =
// pane height / (2 tan(fov / 2)).
export function renderPane(renderer, pane, camera) {
  const r = paneRect(renderer, pane);
  if (pane.material) {
    const tanHalf = Math.tan(THREE.MathUtils.degToRad(camera.fov / 2));
    pane.material.uniforms.uFocalPx.value = r.height / (2 * tanHalf);
  }
  // three's viewport and scissor are in CSS pixels from the bottom left.
  const ratio = renderer.getPixelRatio();
  const bottom = renderer.domElement.height - r.y - r.height;
  renderer.setViewport(r.x / ratio, bottom / ratio, r.width / ratio, r.height / ratio);
  renderer.setScissor(r.x / ratio, bottom / ratio, r.width / ratio, r.height / ratio);
  renderer.setScissorTest(true);
  renderer.setClearColor(BACKGROUND_COLOR, 1);
  renderer.clear();
  renderer.render(pane.scene, camera);
  renderer.setScissorTest(false);
  renderer.getContext().flush();
}

// Clears the whole canvas to transparent (before drawing every pane, should the panes have moved).
export function clearCanvas(renderer) {
  renderer.setScissorTest(false);
  renderer.setClearColor(BACKGROUND_COLOR, 0);
  renderer.clear();
}

// Waits until the drawing is finished by reading one pixel back (used once, for the first
// frames, so that the load time includes the drawing).
export function waitForDrawing(renderer) {
  const gl = renderer.getContext();
  gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
}

// Sets a uniform on the pane's surfel material (no-op for an empty map).
export function setPaneUniform(pane, name, value) {
  if (pane.material) pane.material.uniforms[name].value = value;
}
