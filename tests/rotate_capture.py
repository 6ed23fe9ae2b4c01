#!/usr/bin/env python3
"""A TUM capture turned a quarter turn about the optical axis: every image (rgb/, depth/ and, when
present, the truth/ that punch-holes.py writes) rotated 90 degrees clockwise, camera.json and the
ground truth changed to match. The camera is the same physical one held on its side, so a capture
that moves sideways becomes one that moves vertically in its (portrait, 480x640) images: real
frames for the vertical-motion paths (SGBM on transposed images), which no capture we have holds.

Usage: rotate_capture.py SRC DST

Pixel (u, v) of a W x H image goes to (H - 1 - v, u). With the new camera axes x' = -y, y' = x,
z' = z: fx' = fy, fy' = fx, cx' = H - 1 - cy, cy' = cx; the radial distortion terms are unchanged
and the tangential ones become p1' = p2, p2' = -p1 (Brown-Conrady, as OpenCV and camera.json);
each ground-truth pose world_from_camera is followed by camera_from_rotated (z' = z, a quarter
turn). The depth sensor's rows turn with the images (a camera held on its side would still read
its rows down its own images): camera.json's depth_readout_order says so (the first row is now
the last column).
"""
import json
import os
import shutil
import sys

import cv2
import numpy as np

# camera_from_rotated (x = y', y = -x', z = z': a quarter turn about z, -90 degrees) as a unit
# quaternion (x, y, z, w).
CAMERA_FROM_ROTATED = np.array([0.0, 0.0, -np.sqrt(0.5), np.sqrt(0.5)])


def compose(a, b):
    """The quaternion (x, y, z, w) of rotation a followed in its frame by b: a * b (Hamilton)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz])


def rotate_camera(camera):
    width, height = camera["width"], camera["height"]
    out = dict(camera)
    out.update(width=height, height=width, fx=camera["fy"], fy=camera["fx"],
               cx=height - 1 - camera["cy"], cy=camera["cx"])
    d = list(camera.get("distortion", []))
    if len(d) >= 4:
        d[2], d[3] = d[3], -d[2]
        out["distortion"] = d
    # The sensor's lines turn with the image: its first row becomes the last column.
    turned = {"top_to_bottom": "right_to_left", "right_to_left": "bottom_to_top",
              "bottom_to_top": "left_to_right", "left_to_right": "top_to_bottom"}
    out["depth_readout_order"] = turned[camera.get("depth_readout_order", "top_to_bottom")]
    return out


def main(src, dst):
    os.makedirs(dst, exist_ok=True)
    with open(os.path.join(src, "camera.json")) as f:
        camera = json.load(f)
    with open(os.path.join(dst, "camera.json"), "w") as f:
        json.dump(rotate_camera(camera), f, indent=1)
    for folder in ["rgb", "depth", "truth"]:
        if not os.path.isdir(os.path.join(src, folder)):
            continue
        os.makedirs(os.path.join(dst, folder), exist_ok=True)
        for name in sorted(os.listdir(os.path.join(src, folder))):
            image = cv2.imread(os.path.join(src, folder, name), cv2.IMREAD_UNCHANGED)
            if image is None:
                sys.exit(f"rotate_capture: {os.path.join(src, folder, name)}: not an image")
            cv2.imwrite(os.path.join(dst, folder, name), cv2.rotate(image, cv2.ROTATE_90_CLOCKWISE))
    for name in ["rgb.txt", "depth.txt"]:
        shutil.copy(os.path.join(src, name), os.path.join(dst, name))
    with open(os.path.join(src, "groundtruth.txt")) as f, \
            open(os.path.join(dst, "groundtruth.txt"), "w") as out:
        for line in f:
            if line.startswith("#") or not line.strip():
                out.write(line)
                continue
            v = line.split()
            q = compose(np.array(v[4:8], dtype=float), CAMERA_FROM_ROTATED)
            out.write(" ".join(v[:4] + ["%.7f" % c for c in q]) + "\n")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
