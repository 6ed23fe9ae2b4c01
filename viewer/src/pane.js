// One pane: a WebGL renderer on the pane's canvas and a scene with the map's surfels and the
// camera path/frusta. All panes render the same shared camera.
import * as THREE from 'three';
import { BACKGROUND } from './dom.js';
import { createSurfelMaterial } from './surfel_material.js';
import { buildPathAndFrusta } from './scene_extras.js';

// Creates the pane's renderer and scene. layoutPane: from dom.buildLayout; map: the parsed map
// ({ geometry, count } or null); extras: arguments for buildPathAndFrusta.
export function createPane(layoutPane, map, confRange, extras) {
  const renderer = new THREE.WebGLRenderer({
    canvas: layoutPane.canvas,
    antialias: false,             // MSAA would cost 4x the fill in software rendering
    preserveDrawingBuffer: true,  // lets the test (and a person) read the canvas back
    powerPreference: 'high-performance',
  });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(new THREE.Color(BACKGROUND), 1);
  const gl = renderer.getContext();
  const maxPointPx = gl.getParameter(gl.ALIASED_POINT_SIZE_RANGE)[1];
  layoutPane.canvas.dataset.maxPointPx = String(maxPointPx);

  const scene = new THREE.Scene();
  let material = null;
  if (map && map.count > 0) {
    material = createSurfelMaterial({ maxPointPx, confRange });
    const points = new THREE.Points(map.geometry, material);
    points.frustumCulled = false;  // the bounding sphere is not needed; skip computing it
    scene.add(points);
  }
  const overlay = buildPathAndFrusta(extras);
  scene.add(overlay.group);
  return { layoutPane, renderer, scene, material, overlay };
}

// Matches the drawing buffer to the canvas's CSS size (times the device pixel ratio) and the
// disc size scale to the view: focal (framebuffer px) = buffer height / (2 tan(fov / 2)).
export function resizePane(pane, camera) {
  const box = pane.layoutPane.box;
  pane.size = `${box.clientWidth}x${box.clientHeight}`;  // what the pane was sized for
  const w = Math.max(1, box.clientWidth);
  const h = Math.max(1, box.clientHeight);
  pane.renderer.setSize(w, h, false);
  if (pane.material) {
    const bufferHeight = pane.renderer.getContext().drawingBufferHeight;
    const tanHalf = Math.tan(THREE.MathUtils.degToRad(camera.fov / 2));
    pane.material.uniforms.uFocalPx.value = bufferHeight / (2 * tanHalf);
  }
  return w / h;
}

// Draws the pane and hands the commands to the GPU process without waiting for them.
export function renderPane(pane, camera) {
  pane.renderer.render(pane.scene, camera);
  pane.renderer.getContext().flush();
}

// Waits until the pane's drawing is finished by reading one pixel back (used once, for the
// first frame, so that the load time includes the drawing).
export function waitForPane(pane) {
  const gl = pane.renderer.getContext();
  gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
}

// Sets a uniform on the pane's surfel material (no-op for an empty map).
export function setPaneUniform(pane, name, value) {
  if (pane.material) pane.material.uniforms[name].value = value;
}
