// Writes synthetic viewer test pages, each a folder with report.html (the page contract of
// README.md), view_data.js (window.GF_VIEW) and a freshly built gf_viewer.js:
//   OUTDIR/report.html         a "with fill" map of N surfels and a smaller "without fill" map
//   OUTDIR/small/report.html   the same scene with 20,000 surfels, for quick iteration
// Usage: node make_big_view.mjs OUTDIR [N=1000000] [--one-map] [--empty-second] [--no-keyframes]
//                                [--page-cap M]
//   --page-cap M    at most M surfels of each map on the page, evenly spread, as a report keeps
//                   them (apps/map_view.h kMaxViewSurfels); the page states the full count
//   --one-map       only the "with fill" map (a plain run)
//   --empty-second  the "without fill" map has zero surfels
//   --no-keyframes  no keyframes (the path is still drawn)
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { PNG } from 'pngjs';
import { sampleScene, cameraPath, poseMatrix } from './synth_scene.mjs';
import { surfelPlyBytes } from './ply_writer.mjs';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const SMALL_N = 20000;

function parseArgs(argv) {
  const flags = new Set(argv.filter((a) => a.startsWith('--')));
  const capValue = argv.indexOf('--page-cap') >= 0 ? argv[argv.indexOf('--page-cap') + 1] : null;
  const rest = argv.filter((a) => !a.startsWith('--') && a !== capValue);
  if (rest.length < 1) {
    console.error('usage: node make_big_view.mjs OUTDIR [N] [--one-map] [--empty-second] [--no-keyframes]');
    process.exit(2);
  }
  const n = rest[1] ? Number(rest[1]) : 1000000;
  if (!Number.isInteger(n) || n < 0) throw new Error(`bad surfel count ${rest[1]}`);
  const capAt = argv.indexOf('--page-cap');
  const pageCap = capAt >= 0 ? Number(argv[capAt + 1]) : Infinity;
  return { out: path.resolve(rest[0]), n, pageCap, oneMap: flags.has('--one-map'),
    emptySecond: flags.has('--empty-second'), noKeyframes: flags.has('--no-keyframes') };
}

// A map entry of GF_VIEW. claimTotal: the surfels_total to state (>= shown means subsampled).
// As the reports carry a map: without normals, base64 in chunks of 256 KiB (apps/map_view.cc).
function mapEntry(name, surfels, claimTotal) {
  const text = surfelPlyBytes(surfels, { normals: false }).toString('base64');
  const chunks = [];
  for (let i = 0; i < text.length; i += 262144) chunks.push(text.slice(i, i + 262144));
  return { name, ply_base64: chunks, surfels_total: claimTotal, surfels_shown: surfels.count };
}

// A 160x120 stand-in fill overlay: a grey gradient with a green "filled" block.
function writeOverlayPng(file, seed) {
  const png = new PNG({ width: 160, height: 120 });
  for (let y = 0; y < 120; y++) {
    for (let x = 0; x < 160; x++) {
      const i = 4 * (y * 160 + x);
      const filled = x > 20 + seed * 8 && x < 90 + seed * 8 && y > 25 && y < 95;
      const g = 60 + x / 2;
      png.data.set(filled ? [27, 120, 55, 255] : [g, g, g, 255], i);
    }
  }
  fs.writeFileSync(file, PNG.sync.write(png));
}

// Keyframes every 15th frame; the last has no overlay (a keyframe without a fill).
function keyframes(dir, poses) {
  fs.mkdirSync(path.join(dir, 'keyframes'), { recursive: true });
  const out = [];
  for (let f = 0, k = 0; f < poses.length; f += 15, k++) {
    const label = (1305031102.175 + f / 30).toFixed(3);
    const last = f + 15 >= poses.length;
    const overlay = last ? '' : `keyframes/${label}.fill_overlay.png`;
    if (overlay) writeOverlayPng(path.join(dir, overlay), k);
    out.push({ label, world_from_camera: poseMatrix(poses[f]), overlay });
  }
  return out;
}

// The surfels a report's page holds of a map of s.count: every one up to `cap`, else `cap` of
// them evenly spread, as the C++ writer keeps them (apps/map_view.cc ForThePage).
function forThePage(s, cap) {
  if (!(s.count > cap)) return s;
  const keep = [];
  for (let i = 0; i < s.count; i++) {
    if (Math.floor(((i + 1) * cap) / s.count) > Math.floor((i * cap) / s.count)) keep.push(i);
  }
  const pick = (a, k) => keep.flatMap((i) => Array.from({ length: k }, (_, j) => a[k * i + j]));
  return { count: keep.length, pos: pick(s.pos, 3), nrm: pick(s.nrm, 3), rgb: pick(s.rgb, 3),
    radius: pick(s.radius, 1), conf: pick(s.conf, 1), source: pick(s.source, 1) };
}

// Writes one page folder with n surfels in the "with fill" map (at most opts.pageCap of each map
// on the page, the total stated).
function writePage(dir, n, opts, bundle) {
  fs.mkdirSync(dir, { recursive: true });
  const withFill = sampleScene(n, true, 11);
  const maps = [mapEntry('with fill', forThePage(withFill, opts.pageCap),
    dir.endsWith('small') ? 4 * n : n)];
  if (!opts.oneMap) {
    const without = opts.emptySecond ? { count: 0, pos: [], nrm: [], rgb: [], radius: [], conf: [], source: [] }
      : sampleScene(Math.round(n / 4), false, 12);
    maps.push(mapEntry('without fill', forThePage(without, opts.pageCap), without.count));
  }
  const poses = cameraPath(120);
  const view = {
    maps,
    trajectory: poses.map((p) => p.c),
    keyframes: opts.noKeyframes ? [] : keyframes(dir, poses),
    camera: { width: 640, height: 480, fx: 525, fy: 525, cx: 319.5, cy: 239.5 },
  };
  fs.writeFileSync(path.join(dir, 'view_data.js'), `window.GF_VIEW = ${JSON.stringify(view)};\n`);
  fs.writeFileSync(path.join(dir, 'report.html'), reportHtml(n));
  fs.copyFileSync(bundle, path.join(dir, 'gf_viewer.js'));
  const counts = maps.map((m) => `${m.name}: ${m.surfels_shown}`).join(', ');
  console.log(`wrote ${path.join(dir, 'report.html')} (${counts})`);
}

function reportHtml(n) {
  return `<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>GlassFusion viewer test (${n} surfels)</title></head>
<body>
<h1>Synthetic GlassFusion map view</h1>
<div id="gf-view"></div>
<script src="view_data.js"></script>
<script src="gf_viewer.js"></script>
<script>GFViewer.mount(document.getElementById('gf-view'), window.GF_VIEW);</script>
</body></html>
`;
}

function main() {
  const opts = parseArgs(process.argv.slice(2));
  const buildDir = fs.mkdtempSync(path.join(os.tmpdir(), 'gf_viewer_build_'));
  try {
    execFileSync('bash', [path.join(HERE, '..', 'build.sh'), buildDir], { stdio: ['ignore', 'ignore', 'inherit'] });
    const bundle = path.join(buildDir, 'gf_viewer.js');
    writePage(opts.out, opts.n, opts, bundle);
    writePage(path.join(opts.out, 'small'), SMALL_N, opts, bundle);
  } finally {
    fs.rmSync(buildDir, { recursive: true, force: true });
  }
}

main();
