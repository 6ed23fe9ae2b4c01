#!/usr/bin/env python3
"""Scores `glassfusion fill-frame` outputs on the ClearGrasp D435 frames (issue 54's figures).

Usage: glass_frame_eval.py CLEARGRASP_DIR ID OUT_DIR [ID OUT_DIR ...]
  CLEARGRASP_DIR: ../shared/datasets/glass_real_frames/cleargrasp_d435 (or a folder like it)
  ID: a frame id (000000080); OUT_DIR: the folder fill-frame wrote for it.
Prints, per frame: the object pixels (ClearGrasp mask) whose depth is within 1 cm of the true
surface (the opaque copy's depth), over those with a true depth, for the raw sensor and for
depth_filled.png; the glass mask's IoU with the object mask; and how many pixels outside the
objects fill-frame changed by more than 1 cm (damage). Needs numpy and OpenCV (python3-opencv).
"""
import os
import sys

os.environ.setdefault("OPENCV_IO_ENABLE_OPENEXR", "1")
import cv2  # noqa: E402
import numpy as np  # noqa: E402


def score(folder, frame_id, out_dir):
    read = lambda name: cv2.imread(os.path.join(folder, f"{frame_id}-{name}"), cv2.IMREAD_UNCHANGED)
    mask = read("mask.png") > 0
    raw = read("transparent-depth-img.exr")[..., 0]
    truth = read("opaque-depth-img.exr")[..., 0]
    filled = cv2.imread(os.path.join(out_dir, "depth_filled.png"), cv2.IMREAD_UNCHANGED) / 1000.0
    found = cv2.imread(os.path.join(out_dir, "glass_mask.png"), cv2.IMREAD_UNCHANGED) > 0
    known = mask & (truth > 0)
    within = lambda d: float((np.abs(d - truth)[known] < 0.01).mean())
    raw_mm = np.round(raw * 1000) / 1000  # as fill-frame reads it back, in millimetres
    outside = ~mask & (raw > 0)
    damaged = int((np.abs(filled - raw_mm)[outside] > 0.01).sum())
    iou = float((found & mask).sum() / max(1, (found | mask).sum()))
    return within(raw), within(filled), iou, damaged, int(outside.sum())


def main(argv):
    if len(argv) < 4 or len(argv) % 2:
        sys.exit(__doc__)
    print("frame      raw<1cm  filled<1cm  mask IoU  changed >1cm outside the objects")
    for frame_id, out_dir in zip(argv[2::2], argv[3::2]):
        raw, filled, iou, damaged, outside = score(argv[1], frame_id, out_dir)
        print(f"{frame_id}  {raw:7.3f}  {filled:10.3f}  {iou:8.3f}  {damaged} of {outside} px")


if __name__ == "__main__":
    main(sys.argv)
