// The camera path and keyframe frusta, built once per pane (a three.js object lives in one
// scene), and picking a keyframe from a click.
import * as THREE from 'three';

const PATH_COLOR = 0xff7f0e;      // orange
const FRUSTUM_COLOR = 0xd62728;   // red
const SELECTED_COLOR = 0xffeb3b;  // yellow

// Row-major 4x4 world_from_camera (16 numbers) -> THREE.Matrix4, or null if malformed.
export function poseToMatrix(values) {
  if (!Array.isArray(values) || values.length !== 16 || !values.every(Number.isFinite)) return null;
  return new THREE.Matrix4().set(...values);
}

// Frustum depth (metres): ~6% of the scene's radius, but at most 1.5 times the median distance
// between consecutive keyframes so that dense keyframes do not pile up; within 3 cm .. 40 cm.
export function frustumDepth(sceneRadius, keyframes) {
  const gaps = [];
  const a = new THREE.Vector3();
  const b = new THREE.Vector3();
  for (let i = 1; i < keyframes.length; i++) {
    gaps.push(a.setFromMatrixPosition(keyframes[i - 1].matrix).distanceTo(b.setFromMatrixPosition(keyframes[i].matrix)));
  }
  gaps.sort((p, q) => p - q);
  let depth = 0.06 * sceneRadius;
  if (gaps.length > 0) depth = Math.min(depth, 1.5 * gaps[Math.floor(gaps.length / 2)]);
  return Math.min(0.4, Math.max(0.03, depth));
}

// Apex and the four image-corner points at `depth` metres, camera frame (x right, y down,
// z forward), from the pinhole intrinsics (pixels).
function frustumCorners(cam, depth) {
  const pix = [[0, 0], [cam.width, 0], [cam.width, cam.height], [0, cam.height]];
  return pix.map(([u, v]) => new THREE.Vector3(
    ((u - cam.cx) / cam.fx) * depth, ((v - cam.cy) / cam.fy) * depth, depth));
}

// Line segments of one frustum in the camera frame: 4 edges from the centre, the image
// rectangle, and a small triangle over the top edge marking "up" in the image.
function frustumGeometry(cam, depth) {
  const o = new THREE.Vector3();
  const [a, b, c, d] = frustumCorners(cam, depth);
  const topMid = a.clone().add(b).multiplyScalar(0.5);
  const tip = topMid.clone().add(new THREE.Vector3(0, -0.25 * (d.y - a.y), 0));
  const pts = [o, a, o, b, o, c, o, d, a, b, b, c, c, d, d, a,
    a.clone().lerp(b, 0.3), tip, tip, b.clone().lerp(a, 0.3)];
  return new THREE.BufferGeometry().setFromPoints(pts);
}

// A group holding the path line and the frusta. keyframes: [{ matrix }], trajectory: [[x,y,z]].
// Returns { group, setSelected(index) }.
export function buildPathAndFrusta({ trajectory, keyframes, camera, depth }) {
  const group = new THREE.Group();
  const pathPts = trajectory.filter((p) => Array.isArray(p) && p.length === 3 && p.every(Number.isFinite));
  if (pathPts.length >= 2) {
    const geom = new THREE.BufferGeometry().setFromPoints(pathPts.map((p) => new THREE.Vector3(...p)));
    group.add(new THREE.Line(geom, new THREE.LineBasicMaterial({ color: PATH_COLOR })));
  }
  const normal = new THREE.LineBasicMaterial({ color: FRUSTUM_COLOR });
  const selected = new THREE.LineBasicMaterial({ color: SELECTED_COLOR });
  const geom = frustumGeometry(camera, depth);
  const frusta = keyframes.map((kf) => {
    const lines = new THREE.LineSegments(geom, normal);
    lines.matrixAutoUpdate = false;
    lines.matrix.copy(kf.matrix);
    group.add(lines);
    return lines;
  });
  function setSelected(index) {
    frusta.forEach((f, i) => { f.material = i === index ? selected : normal; });
  }
  return { group, setSelected };
}

// The keyframe whose pick sphere (centred half-way along the frustum, radius about its size)
// the ray through `ndc` (normalised device coordinates of the click) hits first, or -1.
export function pickKeyframe(keyframes, viewCamera, ndc, depth) {
  const raycaster = new THREE.Raycaster();
  raycaster.setFromCamera(ndc, viewCamera);
  const hit = new THREE.Vector3();
  let best = -1;
  let bestDist = Infinity;
  keyframes.forEach((kf, i) => {
    const centre = new THREE.Vector3(0, 0, depth / 2).applyMatrix4(kf.matrix);
    const sphere = new THREE.Sphere(centre, depth * 0.75);
    if (raycaster.ray.intersectSphere(sphere, hit)) {
      const dist = hit.distanceTo(raycaster.ray.origin);
      if (dist < bestDist) { bestDist = dist; best = i; }
    }
  });
  return best;
}
