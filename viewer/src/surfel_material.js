// The surfel shader: each surfel is a THREE.Points vertex drawn as a round, screen-facing disc
// whose size on screen matches its world radius.
//   point size (framebuffer pixels) = 2 * radius (m) * focal (px) / view depth (m),
// clamped to [uMinPointPx, uMaxPointPx]. Fragments outside the inscribed circle are discarded.
// Colours are sRGB and written to the canvas as they are (no tone mapping, no conversion).
import * as THREE from 'three';
import { MAX_SOURCE_ID, sourceColorTable } from './sources.js';

// uColorMode values, as in the colour select's options.
export const COLOR_MODES = { rgb: 0, source: 1, confidence: 2 };

const VERTEX_SHADER = /* glsl */ `
// One vertex per surfel row (ply.js): each property's bytes as unsigned bytes, not normalised
// (0..255), so the shader reads the file's rows as they are.
attribute vec4 xBytes;           // position (world frame, metres): float32 little-endian bytes
attribute vec4 yBytes;
attribute vec4 zBytes;
attribute vec3 rgbBytes;         // surfel colour, 0..255 sRGB
attribute vec4 radiusBytes;      // disc radius (metres), float32 bytes
attribute vec4 confidenceBytes;  // accumulated measurement weight, float32 bytes
attribute float sourceByte;      // DepthSource number

uniform float uFocalPx;     // focal length of the view, framebuffer pixels
uniform float uMinPointPx;  // clamp of the disc diameter, framebuffer pixels
uniform float uMaxPointPx;
uniform int uColorMode;     // 0 rgb, 1 source, 2 confidence
uniform int uSourceMask;    // bit n set: surfels of source n are shown
uniform vec3 uSourceColors[${MAX_SOURCE_ID + 1}];
uniform vec2 uConfRange;    // confidence mapped to the ends of the ramp

varying vec3 vColor;
varying float vSizePx;

// The float32 whose little-endian bytes are b (each 0..255).
float floatFromBytes(vec4 b) {
  uvec4 u = uvec4(b);
  return uintBitsToFloat(u.x | (u.y << 8) | (u.z << 16) | (u.w << 24));
}

// Confidence ramp, low to high: dark purple, blue, teal, yellow-green, yellow.
vec3 confidenceRamp(float t) {
  vec3 c0 = vec3(0.27, 0.00, 0.33);
  vec3 c1 = vec3(0.23, 0.32, 0.55);
  vec3 c2 = vec3(0.13, 0.57, 0.55);
  vec3 c3 = vec3(0.37, 0.79, 0.38);
  vec3 c4 = vec3(0.99, 0.91, 0.14);
  t = clamp(t, 0.0, 1.0) * 4.0;
  if (t < 1.0) return mix(c0, c1, t);
  if (t < 2.0) return mix(c1, c2, t - 1.0);
  if (t < 3.0) return mix(c2, c3, t - 2.0);
  return mix(c3, c4, t - 3.0);
}

void main() {
  int s = clamp(int(sourceByte + 0.5), 0, ${MAX_SOURCE_ID});
  if (((uSourceMask >> s) & 1) == 0) {
    // Hidden source: put the point outside the clip volume so it is not rasterised.
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    gl_PointSize = 1.0;
    vColor = vec3(0.0);
    vSizePx = 1.0;
    return;
  }
  vec3 surfelPosition = vec3(floatFromBytes(xBytes), floatFromBytes(yBytes), floatFromBytes(zBytes));
  vec4 viewPos = modelViewMatrix * vec4(surfelPosition, 1.0);
  gl_Position = projectionMatrix * viewPos;
  float depth = max(-viewPos.z, 1e-4);
  vSizePx = clamp(2.0 * floatFromBytes(radiusBytes) * uFocalPx / depth, uMinPointPx, uMaxPointPx);
  gl_PointSize = vSizePx;
  if (uColorMode == 1) {
    vColor = uSourceColors[s];
  } else if (uColorMode == 2) {
    float confidence = floatFromBytes(confidenceBytes);
    vColor = confidenceRamp((confidence - uConfRange.x) / max(uConfRange.y - uConfRange.x, 1e-6));
  } else {
    vColor = rgbBytes / 255.0;
  }
}
`;

const FRAGMENT_SHADER = /* glsl */ `
varying vec3 vColor;
varying float vSizePx;

void main() {
  vec2 p = gl_PointCoord * 2.0 - 1.0;  // -1..1 across the point's square
  float r2 = dot(p, p);
  if (r2 > 1.0) discard;               // round disc
  // A slightly darker rim on discs big enough to show it, so overlapping discs read as discs.
  float shade = (vSizePx >= 6.0 && r2 > 0.72) ? 0.75 : 1.0;
  gl_FragColor = vec4(vColor * shade, 1.0);
}
`;

// A material for one pane. maxPointPx: the hardware's largest point size (and at most 64).
export function createSurfelMaterial({ maxPointPx, confRange }) {
  const colors = sourceColorTable().map((c) => new THREE.Vector3(c[0], c[1], c[2]));
  return new THREE.ShaderMaterial({
    vertexShader: VERTEX_SHADER,
    fragmentShader: FRAGMENT_SHADER,
    uniforms: {
      uFocalPx: { value: 500 },
      uMinPointPx: { value: 1 },
      uMaxPointPx: { value: Math.min(64, maxPointPx) },
      uColorMode: { value: COLOR_MODES.rgb },
      uSourceMask: { value: 0xff },
      uSourceColors: { value: colors },
      uConfRange: { value: new THREE.Vector2(confRange[0], confRange[1]) },
    },
  });
}
