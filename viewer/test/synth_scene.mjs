// A synthetic GlassFusion-like scene for the viewer tests: a room corner seen through a
// glass pane, sampled into surfel maps "with fill" and "without fill".
// World frame as GlassFusion's (the first camera's OpenCV frame): x right, y down, z forward,
// metres. The floor is at y = +1 (below the cameras), the back wall at z = 3.

// Deterministic pseudo-random numbers in [0, 1) (a 32-bit xorshift generator).
export function makeRandom(seed) {
  let s = seed >>> 0 || 1;
  return () => {
    s ^= s << 13; s >>>= 0;
    s ^= s >>> 17;
    s ^= s << 5; s >>>= 0;
    return s / 4294967296;
  };
}

// Regions of the scene. Each has an area (m^2), a sampler (u, v in [0,1) -> position and
// normal) and a colour function (position -> [r, g, b] 0..255).
const GLASS = { x0: -1.4, x1: -0.2, y0: -0.6, y1: 0.9, z: 1.6 };
const SPHERE = { c: [0.8, 0.45, 1.9], r: 0.45 };

const REGIONS = [
  {
    name: 'wall', area: 4.0 * 2.5,
    sample: (u, v) => ({ p: [-2 + 4 * u, -1.5 + 2.5 * v, 3.0], n: [0, 0, -1] }),
    color: (p) => (Math.floor((p[0] + 2) / 0.5) % 2 ? [214, 196, 160] : [196, 176, 140]),
  },
  {
    name: 'floor', area: 4.0 * 2.7,
    sample: (u, v) => ({ p: [-2 + 4 * u, 1.0, 0.3 + 2.7 * v], n: [0, -1, 0] }),
    color: (p) => ((Math.floor((p[0] + 2) / 0.5) + Math.floor(p[2] / 0.5)) % 2 ? [120, 96, 70] : [160, 132, 100]),
  },
  {
    name: 'table', area: 0.6 * 0.4,
    sample: (u, v) => ({ p: [-0.2 + 0.6 * u, 0.55, 1.0 + 0.4 * v], n: [0, -1, 0] }),
    color: () => [90, 60, 40],
  },
  {
    name: 'sphere', area: 4 * Math.PI * SPHERE.r * SPHERE.r,
    sample: sampleSphere,
    color: (p) => {
      const shade = 0.55 + 0.45 * Math.max(0, -(p[1] - SPHERE.c[1]) / SPHERE.r);
      return [Math.round(200 * shade), Math.round(50 * shade), Math.round(40 * shade)];
    },
  },
  {
    name: 'glass', area: (GLASS.x1 - GLASS.x0) * (GLASS.y1 - GLASS.y0),
    sample: (u, v) => ({ p: [GLASS.x0 + (GLASS.x1 - GLASS.x0) * u, GLASS.y0 + (GLASS.y1 - GLASS.y0) * v, GLASS.z], n: [0, 0, -1] }),
    color: () => [200, 225, 235],
  },
];

// Uniform point on the sphere (u, v -> z in [-1, 1], azimuth).
function sampleSphere(u, v) {
  const z = 2 * u - 1;
  const a = 2 * Math.PI * v;
  const s = Math.sqrt(1 - z * z);
  const n = [s * Math.cos(a), s * Math.sin(a), z];
  return { p: n.map((c, i) => SPHERE.c[i] + SPHERE.r * c), n };
}

// The source (1..5) a point of a region gets in a map, or 0 when that map lacks it:
// the wall behind the glass is a stereo fill (2), the table a COLMAP fill (3), the floor
// in front of the glass a carried fill (4); the map without fill has holes there.
function classify(region, p, withFill) {
  let fillSource = 0;
  if (region === 'glass') return 5;
  if (region === 'table') fillSource = 3;
  if (region === 'wall' && p[0] > -1.7 && p[0] < -0.05 && p[1] > -0.8 && p[1] < 1.0) fillSource = 2;
  if (region === 'floor' && p[0] > GLASS.x0 && p[0] < GLASS.x1 && p[2] > 1.6 && p[2] < 2.3) fillSource = 4;
  if (fillSource === 0) return 1;
  return withFill ? fillSource : 0;
}

// Samples about `target` surfels of the scene (fewer in the map without fill, which has
// holes). Returns arrays ready for writeSurfelPly.
export function sampleScene(target, withFill, seed) {
  const rand = makeRandom(seed);
  const totalArea = REGIONS.reduce((sum, r) => sum + r.area, 0);
  const spacing = Math.sqrt(totalArea / Math.max(target, 1)); // metres between surfels
  const out = { count: 0, pos: [], nrm: [], rgb: [], radius: [], conf: [], source: [] };
  for (const region of REGIONS) {
    const n = Math.round(target * region.area / totalArea);
    for (let i = 0; i < n; i++) {
      const { p, n: normal } = region.sample(rand(), rand());
      const source = classify(region.name, p, withFill);
      if (source === 0) continue;
      const conf = source === 1 ? 3 + 25 * Math.sqrt(rand()) : 1 + 3 * rand();
      out.pos.push(p[0], p[1], p[2]);
      out.nrm.push(normal[0], normal[1], normal[2]);
      out.rgb.push(...region.color(p));
      out.radius.push(spacing * (0.85 + 0.3 * rand()));
      out.conf.push(conf);
      out.source.push(source);
      out.count++;
    }
  }
  return out;
}

// A camera path sweeping left to right in front of the scene, looking at the back wall.
// Returns world_from_camera poses as { c: centre [3], R: rows of the 3x3 rotation }.
export function cameraPath(frames) {
  const poses = [];
  const look = [0, 0.2, 2.5];
  for (let i = 0; i < frames; i++) {
    const t = frames > 1 ? i / (frames - 1) : 0;
    const c = [-0.8 + 1.6 * t, -0.1 + 0.05 * Math.sin(6 * t), -0.3 + 0.2 * Math.sin(3 * t)];
    const z = normalize(look.map((l, k) => l - c[k]));
    const x = normalize(cross([0, 1, 0], z)); // camera x right, world y is down
    const y = cross(z, x);
    // Columns of R are the camera axes in the world frame.
    poses.push({ c, R: [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]] });
  }
  return poses;
}

// 4x4 row-major world_from_camera of a pose.
export function poseMatrix({ c, R }) {
  return [...R[0], c[0], ...R[1], c[1], ...R[2], c[2], 0, 0, 0, 1];
}

function cross(a, b) {
  return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
}

function normalize(v) {
  const l = Math.hypot(v[0], v[1], v[2]);
  return v.map((c) => c / l);
}
