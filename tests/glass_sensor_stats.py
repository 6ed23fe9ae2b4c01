#!/usr/bin/env python3
"""What a real depth sensor reads on clear objects, for the clear-glass model of `synth`.

Reads the ClearGrasp RealSense D435 frames (../shared/datasets/glass_real_frames/cleargrasp_d435):
  <id>-transparent-depth-img.exr  what the sensor gave (metres, 0 = none)
  <id>-opaque-depth-img.exr       the true surface (objects replaced by painted copies)
  <id>-mask.png                   the clear objects' pixels
  <id>-normals.exr                camera-frame normals of the true surface
and prints, per frame, for the object pixels whose true depth is known:
  - the share with depth, and of those the share behind the true surface by > 1 cm, within 1 cm,
    and in front by > 1 cm;
  - the same shares (of all object pixels: hole / behind / surface / front) by incidence angle
    (angle between the true surface's normal and the ray; 0 = facing the camera) and by distance
    from the mask's edge (pixels, and in a Kinect v1 640x480 image at the same range);
  - how far behind the see-through readings lie: their offset from the true surface, and from a
    proxy of the background behind the object: along each image row, the opaque depth just left
    and just right of the object, interpolated in inverse depth (exact for a plane such as the
    table or the wall behind; rows whose sides have no depth are left out).
Usage: OPENCV_IO_ENABLE_OPENEXR=1 python3 tests/glass_sensor_stats.py [FOLDER]
Needs python3-numpy and python3-opencv (Debian).
"""
import os
import sys

os.environ.setdefault("OPENCV_IO_ENABLE_OPENEXR", "1")
import cv2  # noqa: E402
import numpy as np  # noqa: E402

TOL_M = 0.01
FX, CX, CY = 921.0, 642.0, 359.0  # camera_intrinsics.yaml
KINECT_FX = 525.0


def read_depth(path):
    d = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if d is None:
        sys.exit(f"cannot read {path} (is OPENCV_IO_ENABLE_OPENEXR=1 set?)")
    if d.ndim == 3:
        d = d[:, :, 0]
    return np.nan_to_num(d.astype(np.float32), nan=0.0, posinf=0.0, neginf=0.0)


def incidence_deg(normals):
    """Angle between the normal and the ray towards the camera. The EXR holds (x right, y up,
    z towards the camera), which cv2 returns in the order z, y, x."""
    h, w = normals.shape[:2]
    n = normals[:, :, ::-1].astype(np.float64)  # x, y, z
    u, v = np.meshgrid(np.arange(w), np.arange(h))
    # Ray from the surface to the camera, in the same (x right, y up, z back) frame.
    to_cam = np.stack([-(u - CX) / FX, (v - CY) / FX, np.ones_like(u, dtype=np.float64)], -1)
    to_cam /= np.linalg.norm(to_cam, axis=-1, keepdims=True)
    n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-9)
    c = np.clip(np.abs(np.sum(n * to_cam, axis=-1)), 0, 1)
    return np.degrees(np.arccos(c))


def background_proxy(o, mask, reach=6):
    """Depth of what lies behind the object, estimated along each image row: inverse depth
    interpolated linearly between the opaque depth just left and just right of each run of mask
    pixels (exact for a plane behind the object, such as the table or a wall; 0 where a side has
    no depth within `reach` pixels)."""
    proxy = np.zeros_like(o)
    h, w = o.shape
    for v in range(h):
        row, m = o[v], mask[v]
        edges = np.flatnonzero(np.diff(np.concatenate(([0], m.astype(np.int8), [0]))))
        for a, b in zip(edges[::2], edges[1::2]):  # mask run [a, b)
            left = row[max(0, a - reach):a]
            right = row[b:min(w, b + reach)]
            left, right = left[left > 0], right[right > 0]
            if a == 0 or b == w or left.size == 0 or right.size == 0:
                continue
            il, ir = 1.0 / np.median(left), 1.0 / np.median(right)
            s = (np.arange(a, b) - (a - 0.5)) / (b - a + 1.0)
            proxy[v, a:b] = 1.0 / (il + s * (ir - il))
    return proxy


def classes(t, o):
    """hole / behind / surface / front masks for sensor depth t against the true depth o."""
    hole = t <= 0
    has = ~hole
    return {"hole": hole, "behind": has & (t > o + TOL_M), "surface": has & (np.abs(t - o) <= TOL_M),
            "front": has & (t < o - TOL_M)}


def shares_row(label, sel, cls):
    n = int(sel.sum())
    if n == 0:
        return f"  {label:<22} {n:>7}"
    parts = " ".join(f"{100.0 * (cls[k] & sel).sum() / n:>7.1f}" for k in ("hole", "behind", "surface", "front"))
    return f"  {label:<22} {n:>7} {parts}"


def frame_stats(folder, frame_id):
    p = lambda s: os.path.join(folder, f"{frame_id}-{s}")
    t, o = read_depth(p("transparent-depth-img.exr")), read_depth(p("opaque-depth-img.exr"))
    mask = cv2.imread(p("mask.png"), cv2.IMREAD_GRAYSCALE) > 0
    normals = cv2.imread(p("normals.exr"), cv2.IMREAD_UNCHANGED)
    obj = mask & (o > 0)
    cls = classes(t, o)
    n, has = int(obj.sum()), int((obj & (t > 0)).sum())
    print(f"frame {frame_id}: {n} object pixels with true depth ({int(mask.sum())} in the mask)")
    print(f"  with depth {100.0 * has / n:.1f}%; of those: behind > 1 cm "
          f"{100.0 * (cls['behind'] & obj).sum() / has:.1f}%, within 1 cm "
          f"{100.0 * (cls['surface'] & obj).sum() / has:.1f}%, in front > 1 cm "
          f"{100.0 * (cls['front'] & obj).sum() / has:.1f}%")
    head = f"  {'(% of object pixels)':<22} {'pixels':>7} {'hole':>7} {'behind':>7} {'surface':>7} {'front':>7}"
    print(head)
    print(shares_row("all", obj, cls))
    angle = incidence_deg(normals)
    for lo, hi in ((0, 20), (20, 40), (40, 60), (60, 75), (75, 90.1)):
        print(shares_row(f"incidence {lo}-{int(hi)} deg", obj & (angle >= lo) & (angle < hi), cls))
    edge = cv2.distanceTransform(mask.astype(np.uint8), cv2.DIST_L2, 5)
    for lo, hi in ((0, 4), (4, 10), (10, 25), (25, 1e9)):
        k_lo, k_hi = lo * KINECT_FX / FX, hi * KINECT_FX / FX
        label = f"edge {lo}-{hi if hi < 1e8 else 'inf'} px" + (f" (K {k_lo:.0f}-{k_hi:.0f})" if hi < 1e8 else "")
        print(shares_row(label, obj & (edge >= lo) & (edge < hi), cls))
    # How far behind: offset from the true surface, and from the inpainted background proxy.
    behind = cls["behind"] & obj
    proxy = background_proxy(o, mask)
    behind &= proxy > 0
    off_true = (t - o)[behind]
    off_bg = (t - proxy)[behind]
    q = lambda a: " / ".join(f"{100 * x:.1f}" for x in np.percentile(a, (10, 50, 90)))
    mad = 1.4826 * np.median(np.abs(off_bg - np.median(off_bg)))
    print(f"  behind readings ({behind.sum()}): minus true surface p10/p50/p90 {q(off_true)} cm; "
          f"minus background (row-interpolated) {q(off_bg)} cm (robust sigma {100 * mad:.1f} cm)")
    return {"pixels": n, "hole": 1 - has / n, "behind": behind.sum() / n,
            "surface": (cls["surface"] & obj).sum() / n, "front": (cls["front"] & obj).sum() / n,
            "angle_deg": float(np.median(angle[obj])), "bg_offset_m": float(np.median(off_bg)),
            "bg_sigma_m": float(mad)}


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    folder = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        here, "..", "..", "shared", "datasets", "glass_real_frames", "cleargrasp_d435")
    ids = sorted({f.split("-")[0] for f in os.listdir(folder) if f.endswith("-mask.png")})
    if not ids:
        sys.exit(f"no <id>-mask.png in {folder}")
    results = [frame_stats(folder, i) for i in ids]
    print("\nsummary (% of object pixels)   hole  behind surface  front  median incidence")
    for i, r in zip(ids, results):
        print(f"  {i:<28} {100 * r['hole']:5.1f}  {100 * r['behind']:6.1f}  {100 * r['surface']:6.1f}"
              f"  {100 * r['front']:5.1f}  {r['angle_deg']:5.1f} deg")
    mean = {k: np.mean([r[k] for r in results]) for k in ("hole", "behind", "surface", "front")}
    print(f"  {'mean':<28} {100 * mean['hole']:5.1f}  {100 * mean['behind']:6.1f}  "
          f"{100 * mean['surface']:6.1f}  {100 * mean['front']:5.1f}")


if __name__ == "__main__":
    main()
