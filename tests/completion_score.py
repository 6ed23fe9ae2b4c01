#!/usr/bin/env python3
"""The keyframes' own fill and their completion from the map, scored apart on punched frames.

usage: completion_score.py PUNCHED_DIR RUN_DIR

Every pixel that ../shared/tools/punch-holes.py removed (PUNCHED_DIR/truth/<ts>.png) in a keyframe
of RUN_DIR is scored as fill-eval.py scores it (good: filled within 3% of the removed depth),
split by who filled it: the map's completion (keyframes/<ts>.model_fill.png non-zero) or the
keyframe's own fill (the rest). For the completed pixels, how well the confidence written for them
(keyframes/<ts>.fill_confidence.png, 255 = 1) predicts their error: the good rate of the pixels in
the upper half of the confidence against the lower half (split at the median), and by quarter.
Prints one line per group: pixels, share of the removed pixels, good rate (of the group's pixels,
and of all removed pixels: fill-eval.py's good_rate on the first line), median and 90th
percentile relative error. Needs python3-numpy and python3-opencv.
"""
import glob
import json
import os
import sys

import cv2
import numpy as np


def line(name, errors, removed):
    if len(errors) == 0:
        return f'{name:24s} {0:9d}'
    good = np.mean(errors <= 0.03)
    return (f'{name:24s} {len(errors):9d}  share {len(errors) / max(removed, 1):.3f}  good '
            f'{good:.3f} (of removed {good * len(errors) / max(removed, 1):.3f})  median '
            f'{np.median(errors):.4f}  p90 {np.percentile(errors, 90):.4f}')


def main(punched, run):
    scale = json.load(open(os.path.join(punched, 'camera.json')))['depth_scale']
    own, completed, confidence = [], [], []
    removed = 0
    for filled_path in sorted(glob.glob(os.path.join(run, 'keyframes', '*.depth_filled.png'))):
        ts = os.path.basename(filled_path)[:-len('.depth_filled.png')]
        truth_path = os.path.join(punched, 'truth', ts + '.png')
        if not os.path.exists(truth_path):
            continue
        t = cv2.imread(truth_path, cv2.IMREAD_UNCHANGED).astype(np.float64) / scale
        f = cv2.imread(filled_path, cv2.IMREAD_UNCHANGED).astype(np.float64) / 1000.0
        model_path = os.path.join(run, 'keyframes', ts + '.model_fill.png')
        model = (cv2.imread(model_path, cv2.IMREAD_UNCHANGED) > 0 if os.path.exists(model_path)
                 else np.zeros(t.shape, bool))
        conf_path = os.path.join(run, 'keyframes', ts + '.fill_confidence.png')
        conf = (cv2.imread(conf_path, cv2.IMREAD_UNCHANGED).astype(np.float64) / 255.0
                if os.path.exists(conf_path) else np.zeros(t.shape))
        mask = t > 0
        removed += int(mask.sum())
        hit = mask & (f > 0)
        error = np.abs(f - t) / np.where(t > 0, t, 1)
        own.append(error[hit & ~model])
        completed.append(error[hit & model])
        confidence.append(conf[hit & model])
    own, completed = np.concatenate(own or [[]]), np.concatenate(completed or [[]])
    confidence = np.concatenate(confidence or [[]])
    print(line('all filled', np.concatenate([own, completed]), removed))
    print(line('own fill', own, removed))
    print(line('completed from the map', completed, removed))
    if len(completed) == 0:
        return
    # Upper half of the confidence against the rest (ties at the median go to the lower half).
    median = np.median(confidence)
    print(line(f'  confidence > {median:.2f}', completed[confidence > median], removed))
    print(line(f'  confidence <= {median:.2f}', completed[confidence <= median], removed))
    edges = np.percentile(confidence, [0, 25, 50, 75, 100])
    for q, (lo, hi) in enumerate(zip(edges, edges[1:])):
        sel = (confidence >= lo) & ((confidence < hi) if q < 3 else (confidence <= hi))
        print(line(f'  quarter {q + 1} {lo:.2f}-{hi:.2f}', completed[sel], removed))


if __name__ == '__main__':
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
