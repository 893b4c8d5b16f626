#!/usr/bin/env python3
"""The heap that `scenes/sand_column.json` leaves: its flank's slope (docs/notes/sand.md,
"Sand: column collapse and angle of repose").

The scene is a square column of sand resting on the domain's floor (z = 0, the sticky
ground) that collapses under gravity. This script renders it with --export-particles (or
reads a directory of particle files already written), checks that the last frame is at
rest, and measures the free surface around the column's axis: per bin of radius (width
dx) the highest particle, fitted by a line between 20 % and 80 % of the heap's height
beyond its highest point (the same fit as granular_column.py, refitted once without
outliers beyond 2.5 MADs); angle = atan(-slope). The square column spreads further along
its diagonals than across its faces, so the fit is also made in the two sectors of
+-15 deg around the faces' normals and around the diagonals.

Usage: python3 benches/validation/sand_pile.py OUT_DIR [PARTICLE_DIR]
  Without PARTICLE_DIR, runs target/release/splatter render scenes/sand_column.json
  (SPLATTER overrides the binary) into OUT_DIR. Prints a table and writes
  OUT_DIR/sand_pile.json. Needs numpy.
"""
import json
import math
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from granular_column import robust_line  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
SPLATTER = os.environ.get("SPLATTER", os.path.join(ROOT, "target", "release", "splatter"))
SCENE = os.path.join(ROOT, "scenes", "sand_column.json")


def read_xyz(path):
    """x, y, z and speed of a particle PLY."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    props, n = [], 0
    for line in data[:end].decode().splitlines():
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            n = int(w[2])
        elif w and w[0] == "property":
            props.append((w[2], "<f4" if w[1] == "float" else "<i4"))
    rec = np.frombuffer(data, dtype=np.dtype(props), count=n, offset=end)
    v = np.sqrt(rec["vx"].astype(float) ** 2 + rec["vy"] ** 2 + rec["vz"] ** 2)
    return rec["x"].astype(float), rec["y"].astype(float), rec["z"].astype(float), v


def flank(r, z, dx):
    """Angle (deg) and bin count of the flank fitted on the radial profile."""
    nb = int(r.max() / dx) + 1
    top = np.full(nb, -np.inf)
    np.maximum.at(top, (r / dx).astype(int), z)
    rc = (np.arange(nb) + 0.5) * dx
    ok = np.isfinite(top)
    hmax = top[ok].max()
    peak = rc[ok][np.argmax(top[ok])]
    sel = ok & (rc >= peak) & (top >= 0.2 * hmax) & (top <= 0.8 * hmax)
    if sel.sum() < 3:
        return float("nan"), int(sel.sum())
    return math.degrees(math.atan(-robust_line(rc[sel], top[sel]))), int(sel.sum())


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    scene = json.load(open(SCENE))
    sim = scene["simulation"]
    dx, floor = sim["dx"], sim["domain"]["lo"][2]
    pdir = sys.argv[2] if len(sys.argv) > 2 else os.path.join(out, "particles")
    if len(sys.argv) <= 2:
        env = dict(os.environ)
        env.setdefault("XDG_RUNTIME_DIR", "/tmp/xdg")
        os.makedirs(env["XDG_RUNTIME_DIR"], exist_ok=True)
        subprocess.run([SPLATTER, "render", SCENE, "--out", out, "--width", "160",
                        "--height", "120", "--export-particles", pdir], check=True, env=env)
    files = sorted(f for f in os.listdir(pdir) if f.endswith(".ply"))
    x, y, z, v = read_xyz(os.path.join(pdir, files[-1]))
    cx, cy = [c for c in scene["objects"][1]["transform"]["translate"][:2]]
    dxy = np.stack([x - cx, y - cy])
    r = np.hypot(*dxy)
    theta = np.degrees(np.arctan2(dxy[1], dxy[0])) % 90.0  # fold the square's symmetry
    faces = (theta <= 15) | (theta >= 75)
    diagonals = np.abs(theta - 45) <= 15
    z = z - floor
    height = float(z.max())
    rows = {}
    for name, sel in [("all", np.ones_like(r, dtype=bool)), ("faces", faces),
                      ("diagonals", diagonals)]:
        angle, bins = flank(r[sel], z[sel], dx)
        rows[name] = {"angle_deg": angle, "bins": bins, "radius_m": float(r[sel].max())}
    result = {"frame": len(files) - 1, "particles": int(len(x)), "height_m": height,
              "lowest_m": float(z.min()), "max_speed": float(v.max()), "flank": rows}
    json.dump(result, open(os.path.join(out, "sand_pile.json"), "w"), indent=1)
    print(f"frame {result['frame']}: {len(x)} particles, heap height {height:.4f} m, lowest "
          f"particle {result['lowest_m']:.4f} m above the floor, fastest {v.max():.4f} m/s")
    print("| direction | flank angle | fitted bins | reach from the axis |")
    print("|---|---|---|---|")
    for name, row in rows.items():
        print(f"| {name} | {row['angle_deg']:.1f} deg | {row['bins']} | {row['radius_m']:.3f} m |")


if __name__ == "__main__":
    main()
