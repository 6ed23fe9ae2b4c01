// Mouse/touch interaction: one OrbitControls for the shared camera, attached to whichever
// pane the user is about to drag or scroll, and keyframe picking by click. The events land on
// each pane's surface (dom.js), the element filling the pane's box under the canvas.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { pickKeyframe } from './scene_extras.js';

const CLICK_MAX_MOVE_PX = 5;   // a press that moves further is a drag, not a click
const PICK_TOLERANCE_PX = 12;  // screen distance to a keyframe centre that still picks it

// panes: from createPane; target: initial orbit centre (world, metres);
// onChange(): camera moved; onPick(index): a keyframe was clicked.
export function attachSharedControls({ panes, camera, target, keyframes, depth, onChange, onPick }) {
  const surfaces = panes.map((p) => p.layoutPane.surface);
  const controls = new OrbitControls(camera, surfaces[0]);
  controls.target.copy(target);
  controls.zoomToCursor = true;  // the wheel zooms towards the point under the mouse
  controls.update();
  controls.addEventListener('change', onChange);

  surfaces.forEach((surface) => {
    const box = surface.parentElement;
    // Capture phase on the surface's parent runs before the surface's own listeners, so the
    // controls are on this surface when its pointerdown/wheel reaches them.
    const attach = () => { if (controls.domElement !== surface) controls.connect(surface); };
    box.addEventListener('pointerdown', attach, { capture: true });
    box.addEventListener('wheel', attach, { capture: true, passive: true });
    watchClicks(surface, (ndc, rect) => {
      const index = pickAt(keyframes, camera, ndc, rect, depth);
      if (index >= 0) onPick(index);
    });
  });
  return controls;
}

// Calls onClick(ndc, rect) for a primary-button press and release that hardly moved.
function watchClicks(element, onClick) {
  let down = null;
  element.addEventListener('pointerdown', (e) => {
    down = e.button === 0 ? { x: e.clientX, y: e.clientY } : null;
  });
  element.addEventListener('pointerup', (e) => {
    if (!down || Math.hypot(e.clientX - down.x, e.clientY - down.y) > CLICK_MAX_MOVE_PX) return;
    down = null;
    const rect = element.getBoundingClientRect();
    const ndc = new THREE.Vector2(
      ((e.clientX - rect.left) / rect.width) * 2 - 1,
      -((e.clientY - rect.top) / rect.height) * 2 + 1);
    onClick(ndc, rect);
  });
}

// The keyframe under the click: the first whose pick sphere the ray hits, else the one whose
// frustum centre is on screen within PICK_TOLERANCE_PX of the click (small, far frusta).
function pickAt(keyframes, camera, ndc, rect, depth) {
  if (keyframes.length === 0) return -1;
  const hit = pickKeyframe(keyframes, camera, ndc, depth);
  if (hit >= 0) return hit;
  let best = -1;
  let bestPx = PICK_TOLERANCE_PX;
  keyframes.forEach((kf, i) => {
    const p = new THREE.Vector3(0, 0, depth / 2).applyMatrix4(kf.matrix).project(camera);
    if (p.z < -1 || p.z > 1) return;  // behind the camera or beyond the far plane
    const dx = ((p.x - ndc.x) / 2) * rect.width;
    const dy = ((p.y - ndc.y) / 2) * rect.height;
    const px = Math.hypot(dx, dy);
    if (px < bestPx) { bestPx = px; best = i; }
  });
  return best;
}
