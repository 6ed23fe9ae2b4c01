#!/usr/bin/env python3
"""A long TUM capture from a short one, for memory and endurance runs: its frames replayed forward
then backward (so the motion stays continuous), over and over, re-stamped at 30 Hz, with the
ground truth re-stamped the same way. The images are not copied: rgb/ and depth/ link to SRC's.

Usage: loop_capture.py SRC DST FRAMES
"""
import json
import os
import sys


def read_list(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                rows.append(line.split())
    return rows


def main(src, dst, frames):
    src = os.path.abspath(src)
    rgb = read_list(os.path.join(src, "rgb.txt"))
    depth = read_list(os.path.join(src, "depth.txt"))
    truth = read_list(os.path.join(src, "groundtruth.txt"))
    # Pair colour and depth by order (TUM's association would pair them the same on these lists
    # only if they are already paired: pair each depth with the nearest colour stamp instead).
    pairs = []
    for d in depth:
        t = float(d[0])
        c = min(rgb, key=lambda r: abs(float(r[0]) - t))
        g = min(truth, key=lambda r: abs(float(r[0]) - t))
        if abs(float(c[0]) - t) < 0.02 and abs(float(g[0]) - t) < 0.02:
            pairs.append((c[1], d[1], g[1:]))
    order = list(range(len(pairs))) + list(range(len(pairs) - 2, 0, -1))  # forward, then back
    os.makedirs(dst, exist_ok=True)
    with open(os.path.join(dst, "rgb.txt"), "w") as r, open(os.path.join(dst, "depth.txt"), "w") as d, \
            open(os.path.join(dst, "groundtruth.txt"), "w") as g:
        for f in (r, d, g):
            f.write("# %s replayed forward and back to %d frames (tests/loop_capture.py)\n" % (src, frames))
        for k in range(frames):
            color_file, depth_file, pose = pairs[order[k % len(order)]]
            stamp = "%.6f" % (1000.0 + k / 30.0)
            r.write("%s %s\n" % (stamp, color_file))
            d.write("%s %s\n" % (stamp, depth_file))
            g.write("%s %s\n" % (stamp, " ".join(pose)))
    for sub in ("rgb", "depth"):
        link = os.path.join(dst, sub)
        if not os.path.exists(link):
            os.symlink(os.path.join(src, sub), link)
    with open(os.path.join(src, "camera.json")) as f:
        camera = json.load(f)
    with open(os.path.join(dst, "camera.json"), "w") as f:
        json.dump(camera, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2], int(sys.argv[3])))
