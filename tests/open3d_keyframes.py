#!/usr/bin/env python3
"""A run's keyframes, loaded into Open3D the way the README's outputs section says, agree with the map.

Usage: open3d_keyframes.py RUN_DIR

Reads RUN_DIR/undistorted/ (color/, depth/, camera_intrinsic.json, trajectory.log) with Open3D's own
readers and makes each keyframe's point cloud as a user would (RGBDImage, PointCloud.create_from_
rgbd_image with the intrinsic and the trajectory's extrinsic). Then, for each keyframe, the map
(RUN_DIR/map.ply) is projected through the same intrinsic and extrinsic, nearest point per pixel,
and the keyframe's depth is compared with it where both have one: a wrong pose convention, a wrong
intrinsic or a distorted image read as a pinhole one shows as disagreement, most at the image's
corners. Prints one JSON line; exits 1 when under 90% of those pixels (or of the corners') agree
within 3% of the depth.
"""
import json
import os
import sys

import numpy as np
import open3d as o3d

AGREE = 0.03      # relative depth difference counted as agreeing
MIN_SHARE = 0.90  # share of pixels that must agree, overall and in the corners
CORNER = 0.2      # a corner region: this fraction of the width and of the height


def rendered_depth(points, intrinsic, extrinsic, w, h):
    """The map's depth seen through (intrinsic, extrinsic): nearest point per pixel, inf where none."""
    k = intrinsic.intrinsic_matrix
    p = points @ extrinsic[:3, :3].T + extrinsic[:3, 3]
    p = p[p[:, 2] > 0.1]
    x = np.round(k[0, 0] * p[:, 0] / p[:, 2] + k[0, 2]).astype(int)
    y = np.round(k[1, 1] * p[:, 1] / p[:, 2] + k[1, 2]).astype(int)
    inside = (x >= 0) & (y >= 0) & (x < w) & (y < h)
    z = np.full((h, w), np.inf)
    np.minimum.at(z, (y[inside], x[inside]), p[inside, 2])
    return z


def main(run):
    pinhole = os.path.join(run, "undistorted")
    intrinsic = o3d.io.read_pinhole_camera_intrinsic(os.path.join(pinhole, "camera_intrinsic.json"))
    trajectory = o3d.io.read_pinhole_camera_trajectory(os.path.join(pinhole, "trajectory.log"))
    colors = sorted(os.listdir(os.path.join(pinhole, "color")))
    depths = sorted(os.listdir(os.path.join(pinhole, "depth")))
    if colors != depths or len(colors) != len(trajectory.parameters) or not colors:
        print(json.dumps({"error": "%d colour, %d depth images, %d poses" %
                          (len(colors), len(depths), len(trajectory.parameters))}))
        return 1
    world_map = np.asarray(o3d.io.read_point_cloud(os.path.join(run, "map.ply")).points)
    w, h = intrinsic.width, intrinsic.height
    u, v = np.meshgrid(np.arange(w), np.arange(h))
    corner = ((u < CORNER * w) | (u >= (1 - CORNER) * w)) & ((v < CORNER * h) | (v >= (1 - CORNER) * h))
    agree, both, agree_corner, both_corner, points = 0, 0, 0, 0, 0
    for name, params in zip(colors, trajectory.parameters):
        color = o3d.io.read_image(os.path.join(pinhole, "color", name))
        depth = o3d.io.read_image(os.path.join(pinhole, "depth", name))
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            color, depth, depth_scale=1000.0, depth_trunc=10.0, convert_rgb_to_intensity=False)
        points += len(o3d.geometry.PointCloud.create_from_rgbd_image(
            rgbd, intrinsic, params.extrinsic).points)
        z = np.asarray(rgbd.depth)  # metres
        map_z = rendered_depth(world_map, intrinsic, params.extrinsic, w, h)
        seen = (z > 0) & np.isfinite(map_z)
        good = seen & (np.abs(z - map_z) <= AGREE * map_z)
        agree, both = agree + good.sum(), both + seen.sum()
        agree_corner, both_corner = agree_corner + (good & corner).sum(), both_corner + (seen & corner).sum()
    share, share_corner = agree / max(both, 1), agree_corner / max(both_corner, 1)
    print(json.dumps({"keyframes": len(colors), "points": points, "compared_pixels": int(both),
                      "agree": round(float(share), 4), "corners_agree": round(float(share_corner), 4)}))
    return 0 if share >= MIN_SHARE and share_corner >= MIN_SHARE and points > 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
