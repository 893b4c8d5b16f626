#!/usr/bin/env python3
"""Granular column collapse with the drucker_prager model (docs/notes/sand.md, "Sand: column
collapse and angle of repose").

A quasi-2D (plane-strain) column of sand collapses on a sticky floor against a frictionless
end wall, released from rest with no gate. The slab is one cell thick in y inside a domain
one cell deep, so every grid node lies in the band of the y walls (the grid reaches two
cells past each face of the domain, and the wall band is three cells: src/sim/boundary.rs);
with `"walls": "slip"` those nodes lose their y velocity, which is exactly plane strain.
The x = 0 face is the end wall of Lube et al.'s channel (slip: frictionless), the z = 0
face the floor (sticky).

Measured from the last frame's particles (--export-particles):
  * the runout  (d_inf - d_i) / d_i, d_inf the front of the deposit: the last x bin (bins
    of dx/2) of an unbroken run of occupied bins starting at the wall, so that a stray
    particle thrown ahead does not count;
  * the flank's slope: the free surface h(x) (highest particle per bin of width dx) fitted
    by a line between 20 % and 80 % of the deposit's maximum height, on the flank beyond
    the deposit's highest point; angle = atan(-slope);
  * whether it has come to rest: the largest particle speed and the kinetic energy of the
    last frame against the column's potential energy m g h_i / 2, and how much the runout
    and the angle changed over the last 0.3 s (three frames at 10 fps).

Compared with Lube, Huppert, Sparks & Freundt, "Collapses of two-dimensional granular
columns", Phys. Rev. E 72, 041301 (2005): (d_inf - d_i)/d_i = 1.2 a for a below about
2.3 and 1.9 a^(2/3) above, a = h_i/d_i.

Usage: python3 benches/validation/granular_column.py OUT_DIR [CASE ...]
  CASE is NAME:A:PHI (aspect ratio, friction angle in degrees); the default list is
  runout cases at a = 0.5 and 2 (phi 30) and pile cases at phi 20, 30, 40 (a = 1).
  Writes OUT_DIR/NAME.json, runs target/release/splatter render on it (64x64 pictures,
  particles to OUT_DIR/NAME/particles/), and prints a table; OUT_DIR/results.json holds
  the numbers. Environment: SPLATTER (the binary), DX (grid spacing, default 0.01 m; the
  column is always MIN_CELLS = 20 cells across, so DX sets its size in metres, not the
  resolution).
Needs numpy.
"""
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
SPLATTER = os.environ.get("SPLATTER", os.path.join(ROOT, "target", "release", "splatter"))

DX = float(os.environ.get("DX", "0.01"))
RHO = 1600.0
E = 3.0e5
NU = 0.3
G = 9.8
# Column width in cells: at least 20 across the narrower of width and height.
MIN_CELLS = 20
DEFAULT = ["runout_a0.5:0.5:30", "runout_a2:2:30",
           "pile_phi20:1:20", "pile_phi30:1:30", "pile_phi40:1:40"]


def lube(a):
    """Lube et al. 2005, two-dimensional runout law."""
    return 1.2 * a if a <= 2.3 else 1.9 * a ** (2.0 / 3.0)


def column_size(a):
    """Width d_i and height h_i, the smaller of the two MIN_CELLS cells."""
    if a >= 1.0:
        d = MIN_CELLS * DX
        return d, a * d
    h = MIN_CELLS * DX
    return h / a, h


def scene(a, phi):
    d, h = column_size(a)
    wall = 0.0  # the domain's faces are the walls
    floor = 0.0
    reach = d * (1.0 + 1.6 * max(lube(a), 0.8))  # room for a runout well past Lube's
    hi = [reach + 2 * DX, DX, h + 2 * DX]
    t_end = 4.0 * math.sqrt(h / G) + 0.8 * math.sqrt(reach / G) + 0.5
    fps = 10
    frames = int(math.ceil(t_end * fps)) + 1
    centre = [wall + d / 2, DX / 2, floor + h / 2]
    return {
        "description": f"Plane-strain granular column collapse (benches/validation/granular_column.py): "
                       f"a = {a}, d_i = {d:.3f} m, h_i = {h:.3f} m, drucker_prager phi {phi} deg, "
                       f"E {E:g}, nu {NU}, rho {RHO:g}, dx {DX}; sticky floor, frictionless walls.",
        "output": {"width": 64, "height": 64, "frames": frames, "fps": fps,
                   "background": [0.05, 0.05, 0.08]},
        "camera": {"fov_y_deg": 50, "path": {
            "type": "orbit", "target": [hi[0] / 2, DX / 2, h / 2], "radius": hi[0],
            "height": 0, "start_deg": -90, "turns": 0}},
        "simulation": {
            "dx": DX,
            "domain": {"lo": [0, 0, 0], "hi": hi},
            "gravity": [0, 0, -G],
            "walls": {"kind": "slip"},
            "ground": {"kind": "sticky"},
        },
        "objects": [{
            "name": "column",
            "procedural": {"shape": "box", "size": [d, DX, h], "spacing": DX,
                           "color": [0.82, 0.69, 0.47]},
            "transform": {"translate": centre},
            "physics": {"material": {"model": "drucker_prager", "E": E, "nu": NU,
                                     "density": RHO, "friction_angle": phi}},
        }],
    }, {"a": a, "phi": phi, "d_i": d, "h_i": h, "wall": wall, "floor": floor}


def read_particles(path):
    """x, z, speed, mass of a particle PLY (docs/formats.md, Particle files)."""
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
    return rec["x"].astype(float), rec["z"].astype(float), v, rec["mass"].astype(float)


def measure(pdir, info):
    files = sorted(f for f in os.listdir(pdir) if f.endswith(".ply"))
    r = measure_file(os.path.join(pdir, files[-1]), info)
    # Has the deposit stopped? The same numbers 0.3 s (three frames) earlier.
    early = measure_file(os.path.join(pdir, files[-4]), info)
    r["drift_runout"] = r["runout"] - early["runout"]
    r["drift_angle_deg"] = r["angle_deg"] - early["angle_deg"]
    r["frames"] = len(files)
    return r


def measure_file(path, info):
    x, z, v, m = read_particles(path)
    x = x - info["wall"]
    z = z - info["floor"]
    d, h = info["d_i"], info["h_i"]
    # Front: unbroken run of occupied bins (width dx/2) from the wall.
    bw = DX / 2
    occ = np.zeros(int(x.max() / bw) + 2, dtype=bool)
    occ[np.clip((x / bw).astype(int), 0, None)] = True
    gap = np.flatnonzero(~occ)
    last = (gap[0] if len(gap) else len(occ)) - 1
    front = (last + 1) * bw
    # Free surface: the top particle per dx bin, up to the front.
    nb = int(front / DX) + 1
    idx = np.clip((x / DX).astype(int), 0, nb - 1)
    top = np.full(nb, -np.inf)
    np.maximum.at(top, idx[x <= front], z[x <= front])
    xc = (np.arange(nb) + 0.5) * DX
    ok = np.isfinite(top)
    hmax = top[ok].max()
    peak = xc[ok][np.argmax(top[ok])]
    sel = ok & (xc >= peak) & (top >= 0.2 * hmax) & (top <= 0.8 * hmax)
    angle = float("nan")
    if sel.sum() >= 3:
        slope = robust_line(xc[sel], top[sel])
        angle = math.degrees(math.atan(-slope))
    ke = 0.5 * float((m * v * v).sum())
    pe = float(m.sum()) * G * h / 2
    return {"runout": (front - d) / d, "lube": lube(info["a"]), "front_m": front,
            "h_final_m": float(hmax), "angle_deg": angle, "fit_points": int(sel.sum()),
            "max_speed": float(v.max()), "ke_over_pe": ke / pe}


def robust_line(x, y):
    """Slope of a least-squares line refitted once without points beyond 2.5 MADs."""
    p = np.polyfit(x, y, 1)
    r = y - np.polyval(p, x)
    mad = np.median(np.abs(r - np.median(r))) * 1.4826
    keep = np.abs(r) <= max(2.5 * mad, 1e-9)
    if keep.sum() >= 3:
        p = np.polyfit(x[keep], y[keep], 1)
    return p[0]


def speed_history(pdir):
    out = []
    for f in sorted(f for f in os.listdir(pdir) if f.endswith(".ply")):
        _, _, v, _ = read_particles(os.path.join(pdir, f))
        out.append(round(float(v.max()), 4))
    return out


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    env = dict(os.environ)
    env.setdefault("XDG_RUNTIME_DIR", "/tmp/xdg")
    os.makedirs(env["XDG_RUNTIME_DIR"], exist_ok=True)
    results = {}
    for spec in sys.argv[2:] or DEFAULT:
        name, a, phi = spec.split(":")
        s, info = scene(float(a), float(phi))
        path = os.path.join(out, name + ".json")
        with open(path, "w") as f:
            json.dump(s, f, indent=1)
        run_dir = os.path.join(out, name)
        pdir = os.path.join(run_dir, "particles")
        t0 = time.time()
        subprocess.run([SPLATTER, "render", path, "--out", run_dir, "--checkpoint-every", "0",
                        "--export-particles", pdir], check=True, env=env,
                       stdout=subprocess.DEVNULL)
        r = measure(pdir, info)
        r.update(info)
        r["seconds"] = round(time.time() - t0, 1)
        r["max_speed_per_frame"] = speed_history(pdir)
        results[name] = r
        print(f"{name}: a {r['a']} phi {r['phi']}: runout {r['runout']:.3f} (Lube {r['lube']:.3f}), "
              f"pile angle {r['angle_deg']:.1f} deg over {r['fit_points']} bins, final height "
              f"{r['h_final_m'] / r['d_i']:.3f} d_i, max speed {r['max_speed']:.4f} m/s, "
              f"KE/PE {r['ke_over_pe']:.2e}; change over the last 0.3 s: runout "
              f"{r['drift_runout']:+.3f}, angle {r['drift_angle_deg']:+.1f} deg; {r['seconds']} s",
              flush=True)
    with open(os.path.join(out, "results.json"), "w") as f:
        json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
