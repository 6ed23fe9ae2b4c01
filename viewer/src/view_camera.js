// The one PerspectiveCamera the panes share, and its initial placement.
import * as THREE from 'three';

// Default intrinsics when the page gives none (the TUM RGB-D / Kinect values).
export const DEFAULT_INTRINSICS = { width: 640, height: 480, fx: 525, fy: 525, cx: 319.5, cy: 239.5 };

// Intrinsics from GF_VIEW.camera, falling back to the defaults field by field.
export function intrinsicsFrom(camera) {
  const out = { ...DEFAULT_INTRINSICS };
  for (const key of Object.keys(out)) {
    if (camera && Number.isFinite(camera[key]) && camera[key] > 0) out[key] = camera[key];
  }
  return out;
}

// A camera with the sensor's vertical field of view: 2 atan(height / (2 fy)).
export function createViewCamera(intr) {
  const fovDeg = THREE.MathUtils.radToDeg(2 * Math.atan(intr.height / (2 * intr.fy)));
  return new THREE.PerspectiveCamera(fovDeg, intr.width / intr.height, 0.01, 1000);
}

// Bounding sphere of the union of the maps' robust bounds ({min, max} per map, or null),
// with the keyframe centres and path included so they are in view too.
export function sceneSphere(bounds, points) {
  const box = new THREE.Box3();
  for (const b of bounds) {
    if (b) box.expandByPoint(new THREE.Vector3(...b.min)).expandByPoint(new THREE.Vector3(...b.max));
  }
  for (const p of points) box.expandByPoint(p);
  if (box.isEmpty()) return new THREE.Sphere(new THREE.Vector3(0, 0, 1), 1);
  const sphere = box.getBoundingSphere(new THREE.Sphere());
  sphere.radius = Math.max(sphere.radius, 0.05);
  return sphere;
}

// Places the camera a little behind and above the first keyframe, looking along its viewing
// direction (its camera z axis) with its "up" (its -y axis): the scene much as the sensor first
// saw it, with the camera path and frusta in view. The orbit target is the point on that axis as
// far ahead as the scene's centre. Without keyframes it frames the scene's sphere looking along
// world +z with world -y up (the first camera's view in GlassFusion's world frame). Returns the
// orbit target.
export function placeInitialView(camera, sphere, firstKeyframeMatrix) {
  const forward = new THREE.Vector3(0, 0, 1);
  const up = new THREE.Vector3(0, -1, 0);
  const halfFov = THREE.MathUtils.degToRad(camera.fov / 2);
  let target = sphere.center.clone();
  let position;
  if (firstKeyframeMatrix) {
    const rot = new THREE.Matrix3().setFromMatrix4(firstKeyframeMatrix);
    forward.set(0, 0, 1).applyMatrix3(rot).normalize();
    up.set(0, -1, 0).applyMatrix3(rot).normalize();
    const origin = new THREE.Vector3().setFromMatrixPosition(firstKeyframeMatrix);
    // Metres ahead of the keyframe to the scene's centre (at least 0.3 m).
    const ahead = Math.max(0.3, sphere.center.clone().sub(origin).dot(forward));
    target = origin.clone().addScaledVector(forward, ahead);
    position = origin.clone().addScaledVector(forward, -0.35 * ahead).addScaledVector(up, 0.15 * ahead);
  } else {
    const dist = sphere.radius / Math.sin(Math.min(halfFov, halfFov * camera.aspect)) * 0.85;
    position = sphere.center.clone().addScaledVector(forward, -dist);
  }
  camera.up.copy(up);
  camera.position.copy(position);
  camera.near = Math.max(0.002, sphere.radius * 0.002);
  camera.far = (position.distanceTo(sphere.center) + sphere.radius) * 20;
  camera.lookAt(target);
  camera.updateProjectionMatrix();
  return target;
}
