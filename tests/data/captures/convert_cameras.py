#!/usr/bin/env python3
"""Write the poses of an INRIA cameras.json in the other camera formats splatter reads, as
the tools that make them would: a COLMAP model in text and in binary, a transforms.json and
a nerfstudio camera_path.json with its dataparser_transforms.json. Written from the formats'
own definitions, not from splatter's readers, so that the tests compare independent work.

usage: python3 convert_cameras.py plant_cameras.json plant_formats

- COLMAP (`colmap/sparse/0` text, `colmap_bin/sparse/0` binary): each image's world-to-camera
  R = Rc2w^T as a unit quaternion (qw, qx, qy, qz) and t = -R c, OpenCV axes; one PINHOLE
  camera per image (fx, fy, cx = w/2, cy = h/2); images named 'view_NN.png', listed in
  reverse so that reading them in name order is a real test.
- `transforms.json`: camera-to-world 4x4, OpenGL axes (the y and z columns negated), `w`, `h`,
  and `camera_angle_x` shared at the top (every camera has the same fx), `fl_y` per frame.
- `camera_path.json`: nerfstudio's render path in its normalised world, x_ns = s (T x + t)
  with T a rotation about z by 30 degrees, t = (0.1, -0.2, 0.05), s = 0.8; 16 numbers rows
  first, OpenGL axes; `fov` the vertical field of view in degrees; `dataparser_transforms.json`
  holds T | t and s.
Standard library only; numbers printed with repr (shortest round trip of the float64).
"""
import json
import math
import os
import struct
import sys


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def apply(a, v):
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


def quaternion(r):
    """(w, x, y, z) of a rotation matrix (Shepperd's method)."""
    t = r[0][0] + r[1][1] + r[2][2]
    if t > 0:
        s = 0.5 / math.sqrt(t + 1.0)
        return (0.25 / s, (r[2][1] - r[1][2]) * s, (r[0][2] - r[2][0]) * s, (r[1][0] - r[0][1]) * s)
    i = max(range(3), key=lambda k: r[k][k])
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * math.sqrt(1.0 + r[i][i] - r[j][j] - r[k][k])
    q = [0.0, 0.0, 0.0, 0.0]
    q[0] = (r[k][j] - r[j][k]) / s
    q[1 + i] = 0.25 * s
    q[1 + j] = (r[j][i] + r[i][j]) / s
    q[1 + k] = (r[k][i] + r[i][k]) / s
    return tuple(q)


def orthonormal(r):
    """Gram-Schmidt on the columns, keeping the third (the view axis); the file's rows are
    rounded to six digits."""
    cols = [[r[i][c] for i in range(3)] for c in range(3)]
    z = cols[2]
    n = math.sqrt(sum(v * v for v in z))
    z = [v / n for v in z]
    x = cols[0]
    d = sum(a * b for a, b in zip(x, z))
    x = [a - d * b for a, b in zip(x, z)]
    n = math.sqrt(sum(v * v for v in x))
    x = [v / n for v in x]
    y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]]
    return [[x[i], y[i], z[i]] for i in range(3)]


def main(src, out):
    cams = json.load(open(src))
    order = list(reversed(range(len(cams))))
    for sub in ("colmap/sparse/0", "colmap_bin/sparse/0"):
        os.makedirs(os.path.join(out, sub), exist_ok=True)
    text_cams = ["# Camera list with one line of data per camera:"]
    text_imgs = ["# Image list with two lines of data per image:"]
    bin_cams = struct.pack("<Q", len(cams))
    bin_imgs = struct.pack("<Q", len(cams))
    for k in order:
        c = cams[k]
        cid = k + 1
        w, h = c["width"], c["height"]
        params = (c["fx"], c["fy"], w / 2, h / 2)
        text_cams.append(f"{cid} PINHOLE {w} {h} " + " ".join(repr(float(p)) for p in params))
        bin_cams += struct.pack("<iiQQ4d", cid, 1, w, h, *params)
        r_wc = transpose(orthonormal(c["rotation"]))
        t = [-v for v in apply(r_wc, c["position"])]
        q = quaternion(r_wc)
        name = f"view_{k:02d}.png"
        text_imgs.append(f"{cid} " + " ".join(repr(v) for v in (*q, *t)) + f" {cid} {name}")
        text_imgs.append("")
        bin_imgs += struct.pack("<i7di", cid, *q, *t, cid) + name.encode() + b"\0"
        bin_imgs += struct.pack("<Q", 0)
    with open(os.path.join(out, "colmap/sparse/0/cameras.txt"), "w") as f:
        f.write("\n".join(text_cams) + "\n")
    with open(os.path.join(out, "colmap/sparse/0/images.txt"), "w") as f:
        f.write("\n".join(text_imgs) + "\n")
    with open(os.path.join(out, "colmap_bin/sparse/0/cameras.bin"), "wb") as f:
        f.write(bin_cams)
    with open(os.path.join(out, "colmap_bin/sparse/0/images.bin"), "wb") as f:
        f.write(bin_imgs)

    # transforms.json: OpenGL axes, camera-to-world.
    w0 = cams[0]["width"]
    frames = []
    for k, c in enumerate(cams):
        r = orthonormal(c["rotation"])
        gl = [[r[i][0], -r[i][1], -r[i][2]] for i in range(3)]
        m = [gl[i] + [c["position"][i]] for i in range(3)] + [[0.0, 0.0, 0.0, 1.0]]
        frames.append({"file_path": f"images/view_{k:02d}.png", "transform_matrix": m, "fl_y": c["fy"]})
    transforms = {
        "camera_angle_x": 2.0 * math.atan(0.5 * w0 / cams[0]["fx"]),
        "w": w0,
        "h": cams[0]["height"],
        "frames": frames,
    }
    with open(os.path.join(out, "transforms.json"), "w") as f:
        json.dump(transforms, f, indent=1)

    # nerfstudio: the normalised world x_ns = s (T x + t).
    a = math.radians(30.0)
    T = [[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]]
    tt = [0.1, -0.2, 0.05]
    s = 0.8
    path = []
    for c in cams:
        r = orthonormal(c["rotation"])
        gl = matmul(T, [[r[i][0], -r[i][1], -r[i][2]] for i in range(3)])
        p = [s * (v + d) for v, d in zip(apply(T, c["position"]), tt)]
        m = [gl[0] + [p[0]], gl[1] + [p[1]], gl[2] + [p[2]], [0.0, 0.0, 0.0, 1.0]]
        fov = math.degrees(2.0 * math.atan(0.5 * c["height"] / c["fy"]))
        path.append({"camera_to_world": [v for row in m for v in row], "fov": fov,
                     "aspect": c["width"] / c["height"]})
    with open(os.path.join(out, "camera_path.json"), "w") as f:
        json.dump({"camera_type": "perspective", "render_width": w0, "render_height": cams[0]["height"],
                   "fps": 24, "seconds": len(cams) / 24, "camera_path": path}, f, indent=1)
    with open(os.path.join(out, "dataparser_transforms.json"), "w") as f:
        json.dump({"transform": [T[i] + [tt[i]] for i in range(3)], "scale": s}, f, indent=1)
    print(f"{out}: {len(cams)} cameras as COLMAP text and binary, transforms.json, camera_path.json")


if __name__ == "__main__":
    main(*sys.argv[1:3])
