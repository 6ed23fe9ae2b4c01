#!/usr/bin/env python3
"""Where a fill loses on punched frames (issue 27): every pixel that punch-holes.py removed, scored
as fill-eval.py scores it (good: filled within 3% of the true depth), broken down by what might
explain a miss: the keyframe's fill path, the geometry of its stereo pair (the partner's direction
in the keyframe's camera: forward, sideways, vertical, diagonal) and its baseline, the camera's
speed (from the ground truth), the pixel's distance to the image edge, and (for filled pixels) the
fill's confidence: its good rate per confidence band says how well the confidence predicts error.

Usage: fill_breakdown.py PUNCHED_DIR RUN_DIR
Reads PUNCHED_DIR/truth/<ts>.png, PUNCHED_DIR/camera.json, PUNCHED_DIR/groundtruth.txt,
RUN_DIR/keyframes/<ts>.depth_filled.png and .fill_confidence.png, RUN_DIR/trajectory.txt and
RUN_DIR/report.json.
"""
import collections
import json
import os
import sys

import cv2
import numpy as np


def read_poses(path):
    """TUM trajectory: timestamp -> (position, rotation matrix world_from_camera)."""
    poses = {}
    for line in open(path):
        if not line.strip() or line.startswith('#'):
            continue
        v = [float(x) for x in line.split()]
        x, y, z, w = v[4:8]
        r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                      [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                      [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
        poses[v[0]] = (np.array(v[1:4]), r)
    return poses


def nearest(poses, t):
    key = min(poses, key=lambda k: abs(k - t))
    return poses[key] if abs(key - t) < 0.05 else None


def pair_geometry(poses, t, partner):
    a, b = nearest(poses, t), nearest(poses, partner)
    if a is None or b is None:
        return 'unknown'
    d = a[1].T @ (b[0] - a[0])  # the partner's centre in the keyframe's camera frame
    d = np.abs(d) / max(np.linalg.norm(d), 1e-9)
    if d[2] > 0.7:
        return 'forward'
    if d[0] > 0.7:
        return 'sideways'
    if d[1] > 0.7:
        return 'vertical'
    return 'diagonal'


def speed(truth, t):
    """Camera speed (m/s) over the 0.2 s around t, from the ground truth."""
    a, b = nearest(truth, t - 0.1), nearest(truth, t + 0.1)
    return None if a is None or b is None else np.linalg.norm(b[0] - a[0]) / 0.2


def bucket(value, edges, unit):
    for lo, hi in zip(edges, edges[1:]):
        if value < hi:
            return f'{lo}-{hi} {unit}'
    return f'{edges[-1]}+ {unit}'


def main(punched, run):
    scale = json.load(open(os.path.join(punched, 'camera.json')))['depth_scale']
    truth_poses = read_poses(os.path.join(punched, 'groundtruth.txt'))
    run_poses = read_poses(os.path.join(run, 'trajectory.txt'))
    report = json.load(open(os.path.join(run, 'report.json')))
    tables = collections.defaultdict(lambda: collections.defaultdict(lambda: np.zeros(3)))
    for k in report['fill']['per_keyframe']:
        ts = k['timestamp']
        truth_path = os.path.join(punched, 'truth', ts + '.png')
        filled_path = os.path.join(run, 'keyframes', ts + '.depth_filled.png')
        if not os.path.exists(truth_path) or not os.path.exists(filled_path):
            continue
        t = cv2.imread(truth_path, cv2.IMREAD_UNCHANGED).astype(np.float64) / scale
        f = cv2.imread(filled_path, cv2.IMREAD_UNCHANGED).astype(np.float64) / 1000.0
        removed = t > 0
        if not removed.any():
            continue
        hit = removed & (f > 0)
        good = hit & (np.abs(f - t) <= 0.03 * np.where(t > 0, t, 1))
        partner = k.get('partner')
        geometry = pair_geometry(run_poses, float(ts), float(partner)) if partner else 'no partner'
        v = speed(truth_poses, float(ts))
        rows = {'path': k.get('path', '?'), 'pair geometry': geometry,
                'speed': 'unknown' if v is None else bucket(v, [0, 0.2, 0.3, 0.4], 'm/s'),
                'baseline': bucket(k.get('baseline_m', 0) * 100, [0, 4, 7, 10, 13], 'cm')}
        counts = np.array([removed.sum(), hit.sum(), good.sum()], dtype=float)
        for table, key in rows.items():
            tables[table][key] += counts
        tables['all']['all'] += counts
        # How well the fill's confidence predicts its error: the filled removed pixels by
        # confidence (keyframes/<ts>.fill_confidence.png, 255 = 1).
        conf_path = os.path.join(run, 'keyframes', ts + '.fill_confidence.png')
        if os.path.exists(conf_path):
            c = cv2.imread(conf_path, cv2.IMREAD_UNCHANGED).astype(np.float64) / 255.0
            for lo, hi in [(0, 0.25), (0.25, 0.5), (0.5, 0.75), (0.75, 1.01)]:
                sel = hit & (c >= lo) & (c < hi)
                tables['fill confidence (filled pixels)'][f'{lo:.2f}-{min(hi, 1):.2f}'] += [
                    sel.sum(), sel.sum(), (good & sel).sum()]
        # Distance of each removed pixel to the nearest image edge.
        h, w = t.shape
        ys, xs = np.nonzero(removed)
        edge = np.minimum(np.minimum(xs, w - 1 - xs), np.minimum(ys, h - 1 - ys))
        for lo, hi in [(0, 40), (40, 80), (80, 10**6)]:
            sel = (edge >= lo) & (edge < hi)
            name = f'{lo}-{hi} px' if hi < 10**6 else f'{lo}+ px'
            tables['distance to edge'][name] += [sel.sum(), hit[ys[sel], xs[sel]].sum(),
                                                 good[ys[sel], xs[sel]].sum()]
    for table, rows in tables.items():
        print(f'\n{table}: removed pixels, fill rate, good rate, share of all misses')
        total_miss = tables['all']['all'][0] - tables['all']['all'][2]
        for key, (n, hit, good) in sorted(rows.items()):
            print(f'  {key:28s} {int(n):9d}  {hit / n:.3f}  {good / n:.3f}  '
                  f'{(n - good) / max(total_miss, 1):.3f}')


if __name__ == '__main__':
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
