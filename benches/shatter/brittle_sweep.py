#!/usr/bin/env python3
"""The brittle watermelon's sweep (docs/notes/brittle.md, "A brittle watermelon").

Each run is scenes/watermelon_drop.json with its brittle materials' mean strength scaled
(the flesh's sigma_bar; rind and white rind keep their ratio to it), dropped at another
speed, or on another grid, then rendered with --fragments and measured on its last frame
(solid pieces with >= 1% of the particles, the largest one's share, the share broken
through, and the count linking every particle) and over
all frames (the fastest particle over the drop speed).

Usage:
  python3 benches/shatter/brittle_sweep.py scenes OUT_DIR [RUN ...]
      writes OUT_DIR/NAME.json for each RUN,
      FLESH_STRENGTH:SPEED:DX[:FRAMES[:SEED_SHIFT[:MODULUS[:SOFTENING]]]]
      (SEED_SHIFT is added to every brittle material's seed: another draw of strengths;
      MODULUS replaces every brittle material's Weibull modulus, "u" for uniform strength,
      "-" to keep it; SOFTENING replaces every brittle material's softening ratio)
      (default: the 4 x 3 grid around the shipped point, strengths x 0.75, 1, 1.25, 1.5 and
      speeds x 0.75, 0.875, 1, and the shipped point at dx/1.5);
  python3 benches/shatter/brittle_sweep.py run SPLATTER OUT_DIR
      renders every OUT_DIR/NAME.json not yet done (OUT_DIR/NAME/fragments.csv);
  python3 benches/shatter/brittle_sweep.py report OUT_DIR [CHART.png] [FRAME]
      prints the table as markdown and writes OUT_DIR/sweep.json (and the chart, which
      needs matplotlib), measured at FRAME (default: the shipped scene's last frame) and
      at each run's last frame.
Standard library only, but for the chart.
"""
import copy
import csv
import glob
import json
import os
import subprocess
import sys
import time

SHIPPED_FLESH = None  # read from the scene


def brittle_materials(obj):
    physics = obj["physics"]
    yield physics["material"]
    for r in physics.get("regions", []):
        yield r["material"]


def variant(scene, flesh, speed, dx, frames, shift=0, modulus=None, softening=None):
    v = copy.deepcopy(scene)
    melon = next(o for o in v["objects"] if o.get("name") == "watermelon")
    base = melon["physics"]["material"]["strength"]
    for m in brittle_materials(melon):
        if m.get("model") == "brittle":
            m["strength"] = round(m["strength"] * flesh / base, 6)
            m["seed"] = m.get("seed", 0) + shift
            if modulus == "u":
                m.pop("weibull_modulus", None)
                m.pop("reference_dx", None)
            elif modulus is not None:
                m["weibull_modulus"] = float(modulus)
            if softening is not None:
                m["softening"] = softening
    melon["physics"]["velocity"] = [0, 0, -speed]
    v["simulation"]["dx"] = dx
    v["output"]["frames"] = frames
    v["output"]["width"], v["output"]["height"] = 240, 160
    return v


def name_of(flesh, speed, dx, frames, shift=0, modulus=None, softening=None):
    seed = f"_seed+{shift}" if shift else ""
    m = f"_m{modulus}" if modulus is not None else ""
    soft = f"_soft{softening:g}" if softening is not None else ""
    return f"s{flesh:g}_v{speed:g}_dx{dx:g}_f{frames}{seed}{m}{soft}"


def make(scenes, out, runs):
    scene = json.load(open(os.path.join(scenes, "watermelon_drop.json")))
    melon = next(o for o in scene["objects"] if o.get("name") == "watermelon")
    shipped = melon["physics"]["material"]["strength"]
    speed0 = -melon["physics"]["velocity"][2]
    dx0 = scene["simulation"]["dx"]
    frames0 = scene["output"]["frames"]
    if not runs:
        runs = [f"{shipped * k:g}:{v:g}:{dx0:g}:{frames0}"
                for k in (0.75, 1.0, 1.25, 1.5) for v in (speed0 * 0.75, speed0 * 0.875, speed0)]
        runs.append(f"{shipped:g}:{speed0:g}:{dx0 / 1.5:g}:{frames0}")
    os.makedirs(out, exist_ok=True)
    for r in runs:
        parts = r.split(":")
        flesh, speed, dx = float(parts[0]), float(parts[1]), float(parts[2])
        frames = int(parts[3]) if len(parts) > 3 else frames0
        shift = int(parts[4]) if len(parts) > 4 else 0
        modulus = parts[5] if len(parts) > 5 and parts[5] != "-" else None
        softening = float(parts[6]) if len(parts) > 6 else None
        name = name_of(flesh, speed, dx, frames, shift, modulus, softening)
        path = os.path.join(out, name + ".json")
        json.dump(variant(scene, flesh, speed, dx, frames, shift, modulus, softening),
                  open(path, "w"), indent=1)
        print(path)


def run(splatter, out):
    for path in sorted(glob.glob(os.path.join(out, "*.json"))):
        name = os.path.splitext(os.path.basename(path))[0]
        if name == "sweep":
            continue
        dest = os.path.join(out, name)
        if os.path.exists(os.path.join(dest, "wall_s")):
            continue
        t = time.time()
        subprocess.run([splatter, "render", path, "--out", dest, "--fragments"], check=True,
                       stdout=subprocess.DEVNULL)
        open(os.path.join(dest, "wall_s"), "w").write(f"{time.time() - t:.1f}\n")
        print(name, f"{time.time() - t:.0f} s", flush=True)


def measure(out, at):
    rows = []
    for path in sorted(glob.glob(os.path.join(out, "*.json"))):
        name = os.path.splitext(os.path.basename(path))[0]
        csv_path = os.path.join(out, name, "fragments.csv")
        if name == "sweep" or not os.path.exists(os.path.join(out, name, "wall_s")):
            continue
        scene = json.load(open(path))
        melon = next(o for o in scene["objects"] if o.get("name") == "watermelon")
        frames = [r for r in csv.DictReader(open(csv_path)) if r["object"] == "watermelon"]
        last = frames[min(at, len(frames) - 1)]
        end = frames[-1]
        speed = -melon["physics"]["velocity"][2]
        wall = os.path.join(out, name, "wall_s")
        rows.append({
            "name": name,
            "strength": melon["physics"]["material"]["strength"],
            "speed": speed,
            "dx": scene["simulation"]["dx"],
            "frames": len(frames),
            "particles": int(last["particles"]),
            "pieces": int(last["pieces"]),
            "largest_share": float(last["largest_share"]),
            "damaged_share": float(last["damaged_share"]),
            "debris": int(last["debris"]),
            "linked_pieces": int(last.get("linked_pieces") or 0),
            "linked_largest_share": float(last.get("linked_largest_share") or 0),
            "seed_shift": int(name.split("_seed")[1]) if "_seed" in name else 0,
            "frame": int(last["frame"]),
            "end_frame": int(end["frame"]),
            "end_pieces": int(end["pieces"]),
            "end_largest_share": float(end["largest_share"]),
            "speed_ratio": max(float(r["speed_max"]) for r in frames[1:]) / speed,
            "wall_s": float(open(wall).read()) if os.path.exists(wall) else None,
        })
    return rows


def report(out, chart=None, at=None):
    if at is None:
        shipped = json.load(open(os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                              "..", "..", "scenes", "watermelon_drop.json")))
        at = shipped["output"]["frames"] - 1
    rows = measure(out, at)
    json.dump(rows, open(os.path.join(out, "sweep.json"), "w"), indent=1)
    print(f"Frame {at}, and each run's last frame:\n")
    print("| σ̄ flesh (Pa) | drop (m/s) | Δx (m) | seed shift | particles | pieces ≥ 1% | largest | broken | linked through rubble: pieces, largest | last frame: pieces, largest | v_max / v_drop | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in sorted(rows, key=lambda r: (r["dx"] != max(x["dx"] for x in rows), r["seed_shift"], r["speed"], r["strength"])):
        print(f"| {r['strength']:g} | {r['speed']:g} | {r['dx']:g} | {r['seed_shift']} | {r['particles']} | {r['pieces']} "
              f"| {r['largest_share']:.1%} | {r['damaged_share']:.1%} "
              f"| {r['linked_pieces']}, {r['linked_largest_share']:.1%} "
              f"| {r['end_frame']}: {r['end_pieces']}, {r['end_largest_share']:.1%} "
              f"| {r['speed_ratio']:.2f} | {r['wall_s'] or 0:.0f} |")
    if chart:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        dx0 = max(r["dx"] for r in rows)
        base = [r for r in rows if r["dx"] == dx0 and r["seed_shift"] == 0]
        fig, axes = plt.subplots(1, 3, figsize=(15, 4))
        for speed in sorted({r["speed"] for r in base}):
            pts = sorted((r["strength"], r["pieces"], r["largest_share"], r["damaged_share"])
                         for r in base if r["speed"] == speed)
            for k in range(3):
                axes[k].plot([p[0] for p in pts], [p[k + 1] for p in pts], "o-", label=f"{speed:g} m/s")
        for r in rows:
            if r["seed_shift"] != 0:
                label = f"other seeds, {r['speed']:g} m/s"
                axes[0].plot([r["strength"]], [r["pieces"]], "kx", ms=9, label=label)
                axes[1].plot([r["strength"]], [r["largest_share"]], "kx", ms=9, label=label)
                axes[2].plot([r["strength"]], [r["damaged_share"]], "kx", ms=9, label=label)
            elif r["dx"] != dx0:
                axes[0].plot([r["strength"]], [r["pieces"]], "k*", ms=12, label=f"Δx {r['dx']:g}, {r['speed']:g} m/s")
                axes[1].plot([r["strength"]], [r["largest_share"]], "k*", ms=12, label=f"Δx {r['dx']:g}, {r['speed']:g} m/s")
                axes[2].plot([r["strength"]], [r["damaged_share"]], "k*", ms=12, label=f"Δx {r['dx']:g}, {r['speed']:g} m/s")
        axes[0].set_xlabel("mean flesh strength σ̄ (Pa)")
        axes[0].set_ylabel("solid pieces with ≥ 1% of the particles")
        axes[1].set_xlabel("mean flesh strength σ̄ (Pa)")
        axes[1].set_ylabel("largest piece's share")
        axes[1].axhline(0.5, color="grey", ls=":")
        axes[2].set_xlabel("mean flesh strength σ̄ (Pa)")
        axes[2].set_ylabel("share broken through (rubble)")
        axes[0].axhline(3, color="grey", ls=":")
        handles, labels = axes[0].get_legend_handles_labels()
        unique = dict(zip(labels, handles))
        axes[0].legend(unique.values(), unique.keys(), fontsize=8)
        fig.suptitle(f"Brittle watermelon dropped on a flat table, frame {at} (Δx {dx0:g})")
        fig.tight_layout()
        fig.savefig(chart, dpi=90)


if __name__ == "__main__":
    if len(sys.argv) >= 3 and sys.argv[1] == "run":
        run(sys.argv[2], sys.argv[3])
    elif len(sys.argv) >= 3 and sys.argv[1] == "report":
        report(sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else None,
               int(sys.argv[4]) if len(sys.argv) > 4 else None)
    elif len(sys.argv) >= 3:
        make(sys.argv[1], sys.argv[2], sys.argv[3:])
    else:
        sys.exit(__doc__)
