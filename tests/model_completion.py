#!/usr/bin/env python3
"""How much more of each keyframe's punched holes the fused map could fill than the keyframe's own fill.

usage: model_completion.py PUNCHED_DIR RUN_DIR

Renders RUN_DIR/map.ply (the stable surfels) into every keyframe of the run at the run's own pose
of that keyframe (trajectory.txt; no alignment to the ground truth is needed), each surfel a
square splat of its radius (at most 4 pixels), the nearest depth kept, with the camera's lens
distortion. Scores, as ../shared/tools/fill-eval.py does (share of the removed pixels filled, and
filled within 3% of the removed depth; 90th percentile of the relative error):
  own           the keyframe's own fill (keyframes/<ts>.depth_filled.png: what fill-eval.py scores)
  model         the map's rendering alone
  own + model   the own fill, and the rendering where the own fill left a hole
  model fills   the rendering where its nearest surfel is a fill surfel (source 2)
  own + fills   the own fill, and model fills where it left a hole
On punched frames the patches are anchored with the ground-truth poses, which disagree with the
depth by 1-2 cm, so other frames measure part of what one frame lost: "model" counts those sensor
surfels, "model fills" does not (a glass surface that no frame measures is filled only by fills).
Needs python3-numpy and python3-opencv.
"""
import glob
import json
import os
import sys

import cv2
import numpy as np

SOURCE_STEREO = 2
MAX_SPLAT_PX = 4


def read_surfels(path):
    with open(path, 'rb') as f:
        header = b''
        while not header.endswith(b'end_header\n'):
            line = f.readline()
            if not line:
                raise SystemExit(f'{path}: no PLY header')
            header += line
        lines = header.decode().splitlines()
        count = int(next(l for l in lines if l.startswith('element vertex')).split()[2])
        types = {'float': '<f4', 'uchar': 'u1', 'int': '<i4'}
        dtype = np.dtype([(l.split()[2], types[l.split()[1]]) for l in lines
                          if l.startswith('property')])
        return np.frombuffer(f.read(count * dtype.itemsize), dtype, count)


def quat_to_r(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def render(points, radii, fills, cam, k, dist):
    """Nearest depth per pixel of the camera-frame points, and of the fill points alone."""
    w, h = cam['width'], cam['height']
    keep = points[:, 2] > 0.3
    points, radii, fills = points[keep], radii[keep], fills[keep]
    uv, _ = cv2.projectPoints(points.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), k, dist)
    uv = uv.reshape(-1, 2)
    inside = (np.abs(uv) < 1e5).all(1)
    points, radii, fills, uv = points[inside], radii[inside], fills[inside], uv[inside]
    half = np.clip((radii * cam['fx'] / points[:, 2]).astype(int), 0, MAX_SPLAT_PX)
    u0, v0 = np.round(uv[:, 0]).astype(int), np.round(uv[:, 1]).astype(int)
    out = []
    for subset in (np.ones(len(points), bool), fills):
        depth = np.full((h, w), np.inf)
        for du in range(-MAX_SPLAT_PX, MAX_SPLAT_PX + 1):
            for dv in range(-MAX_SPLAT_PX, MAX_SPLAT_PX + 1):
                s = subset & (abs(du) <= half) & (abs(dv) <= half)
                u, v = u0[s] + du, v0[s] + dv
                ok = (u >= 0) & (v >= 0) & (u < w) & (v < h)
                np.minimum.at(depth, (v[ok], u[ok]), points[s, 2][ok])
        out.append(depth)
    nearest, nearest_fill = out
    model = np.where(np.isfinite(nearest), nearest, 0)
    return model, np.where(np.isfinite(nearest_fill) & (nearest_fill <= nearest), model, 0)


def main():
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    punched, run = sys.argv[1:]
    cam = json.load(open(os.path.join(punched, 'camera.json')))
    k = np.array([[cam['fx'], 0, cam['cx']], [0, cam['fy'], cam['cy']], [0, 0, 1.0]])
    dist = np.array(cam.get('distortion', [0] * 5), float)
    surfels = read_surfels(os.path.join(run, 'map.ply'))
    world = np.stack([surfels['x'], surfels['y'], surfels['z']], 1).astype(np.float64)
    radii = surfels['radius'].astype(np.float64)
    fills = surfels['source'] == SOURCE_STEREO
    poses = np.array([[float(x) for x in l.split()[:8]]
                      for l in open(os.path.join(run, 'trajectory.txt'))
                      if l.strip() and not l.startswith('#')])
    names = ('own', 'model', 'own + model', 'model fills', 'own + fills')
    errors = {n: [] for n in names}
    truth_px = keyframes = 0
    for path in sorted(glob.glob(os.path.join(run, 'keyframes', '*.depth_filled.png'))):
        ts = os.path.basename(path)[:-len('.depth_filled.png')]
        truth_path = os.path.join(punched, 'truth', ts + '.png')
        i = np.argmin(np.abs(poses[:, 0] - float(ts)))
        if not os.path.exists(truth_path) or abs(poses[i, 0] - float(ts)) > 0.02:
            continue
        truth = cv2.imread(truth_path, cv2.IMREAD_UNCHANGED).astype(np.float64) / cam['depth_scale']
        own = cv2.imread(path, cv2.IMREAD_UNCHANGED).astype(np.float64) / 1000.0
        r = quat_to_r(poses[i, 4:8])
        model, model_fills = render((world - poses[i, 1:4]) @ r, radii, fills, cam, k, dist)
        depths = (own, model, np.where(own > 0, own, model), model_fills,
                  np.where(own > 0, own, model_fills))
        removed = truth > 0
        truth_px += removed.sum()
        keyframes += 1
        for name, depth in zip(names, depths):
            hit = removed & (depth > 0)
            errors[name].append(np.abs(depth[hit] - truth[hit]) / truth[hit])
    if not truth_px:
        raise SystemExit('model_completion: no keyframe with punched truth and a pose')
    print(f'{keyframes} keyframes, {truth_px} removed pixels')
    for name in names:
        e = np.concatenate(errors[name])
        p90 = np.percentile(e, 90) if len(e) else float('nan')
        print(f'{name:12s} fill_rate={len(e) / truth_px:.3f} '
              f'good_rate={(e <= 0.03).sum() / truth_px:.3f} p90_rel_err={p90:.4f}')


if __name__ == '__main__':
    main()
