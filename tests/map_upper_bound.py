#!/usr/bin/env python3
"""What ../shared/tools/map-eval.py can score for a run, and what limits it.

usage: map_upper_bound.py PUNCHED_DIR RUN_DIR OUT_DIR

1. Writes OUT_DIR/map.ply and OUT_DIR/trajectory.txt: the removed (true) depth of every punched frame,
   back-projected (lens distortion removed, as the pipeline does) at the run's own pose of that
   frame, one point per 4 mm voxel. No fill or fusion can do better with the run's poses; its
   map-eval score is the ceiling for RUN_DIR's map.
2. Prints map-eval.py's scores of RUN_DIR and of that ceiling twice: with the tool's alignment (Horn
   on camera positions), and with the run aligned by its full poses (positions plus points 0.5 m
   along each camera axis). On a short capture whose camera positions lie almost on a line, the
   positions alone leave the rotation about that line free, and the tool then misplaces even the
   true surfaces; the second figure shows what the map covers where the run is placed right.
Needs python3-numpy and python3-opencv; map-eval.py is found at ../shared/tools beside the project.
"""
import importlib.util
import json
import os
import shutil
import sys

import cv2
import numpy as np

TOOLS = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'shared', 'tools')


def load_map_eval():
    spec = importlib.util.spec_from_file_location('map_eval', os.path.join(TOOLS, 'map-eval.py'))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def poses(path, me):
    rows = np.array([[float(x) for x in l[:8]] for l in me.read_list(path)])
    return rows[:, 0], [(me.quat_to_R(r[4:8]), r[1:4]) for r in rows]


def write_ceiling(punched, run, out, me):
    cam = json.load(open(os.path.join(punched, 'camera.json')))
    fx, fy, cx, cy, s = cam['fx'], cam['fy'], cam['cx'], cam['cy'], cam['depth_scale']
    k = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])
    h, w = cam['height'], cam['width']
    u, v = np.meshgrid(np.arange(w), np.arange(h))
    pixels = np.stack([u, v], -1).reshape(-1, 1, 2).astype(np.float64)
    rays = cv2.undistortPoints(pixels, k, np.array(cam.get('distortion', [0] * 5))).reshape(h, w, 2)
    stamps, est = poses(os.path.join(run, 'trajectory.txt'), me)
    points = []
    for ts, _ in me.read_list(os.path.join(punched, 'depth.txt')):
        truth = os.path.join(punched, 'truth', ts + '.png')
        i = np.argmin(np.abs(stamps - float(ts)))
        if not os.path.exists(truth) or abs(stamps[i] - float(ts)) > 0.02:
            continue
        d = cv2.imread(truth, cv2.IMREAD_UNCHANGED).astype(np.float64) / s
        m = d > 0
        p = np.stack([rays[..., 0][m] * d[m], rays[..., 1][m] * d[m], d[m]], -1)
        r, t = est[i]
        points.append(p @ r.T + t)
    points = np.concatenate(points)
    _, first = np.unique(np.floor(points / 0.004).astype(np.int64), axis=0, return_index=True)
    points = points[first].astype('<f4')
    os.makedirs(out, exist_ok=True)
    shutil.copy(os.path.join(run, 'trajectory.txt'), out)
    with open(os.path.join(out, 'map.ply'), 'wb') as f:
        f.write((f'ply\nformat binary_little_endian 1.0\nelement vertex {len(points)}\n'
                 'property float x\nproperty float y\nproperty float z\nend_header\n').encode())
        f.write(points.tobytes())


def full_pose_alignment(punched, run, me):
    """R, t taking the run's world to the ground truth's, from whole poses (not positions only)."""
    gt_stamps, gt = poses(os.path.join(punched, 'groundtruth.txt'), me)
    stamps, est = poses(os.path.join(run, 'trajectory.txt'), me)
    src, dst = [], []
    for ts, (r, t) in zip(stamps, est):
        i = np.argmin(np.abs(gt_stamps - ts))
        if abs(gt_stamps[i] - ts) >= 0.02:
            continue
        rg, tg = gt[i]
        src.append(t), dst.append(tg)
        for axis in range(3):
            src.append(t + 0.5 * r[:, axis]), dst.append(tg + 0.5 * rg[:, axis])
    return me.horn(np.array(src), np.array(dst))


def score(punched, run, alignment=None):
    """Runs map-eval.py on `run`, with its own alignment or with `alignment` (R, t) instead."""
    tool = load_map_eval()
    if alignment is not None:
        tool.horn = lambda src, dst: alignment
    sys.argv = ['map-eval.py', punched, run]
    tool.main()


def main():
    if len(sys.argv) != 4:
        raise SystemExit(__doc__)
    punched, run, out = sys.argv[1:]
    me = load_map_eval()
    write_ceiling(punched, run, out, me)
    alignment = full_pose_alignment(punched, run, me)  # the ceiling has the run's trajectory
    for label, folder in (('run', run), ('ceiling', out)):
        print(f'{label}, tool alignment:', flush=True)
        score(punched, folder)
        print(f'{label}, full-pose alignment:', flush=True)
        score(punched, folder, alignment)


if __name__ == '__main__':
    main()
