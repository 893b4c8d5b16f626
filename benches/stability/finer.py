#!/usr/bin/env python3
"""Every shipped scene at a finer resolution (docs/notes/stability.md, "Every scene, finer").

Renders each scenes/*.json with `--quality high` (dx and every spacing halved: 8x the
particles) for the first frames at a small image size, and prints per scene: frames
reached, whether the run stopped and why (NaN, escaped, blow-up), particles, the steps of
each simulated frame, how often a frame ran again at half the step, and seconds per
simulated frame. Outside CI: on two CPU cores the
whole list takes about an hour.

Usage:
  python3 benches/stability/finer.py SPLATTER OUT_DIR [--frames N] [--quality Q]
      [--scale S] [--p2g PATH] [--timeout S] [SCENE ...]
      renders into OUT_DIR/NAME/ and writes OUT_DIR/finer.json; prints the table as
      markdown. Defaults: 2 frames (frame 0 and one simulated frame), quality high,
      900 s per scene, every scene in scenes/. --scale S instead multiplies the scene's
      dx and every spacing by S (as `splatter-lab suite --scale S`; quality standard); --p2g
      forces a P2G path (gather, atomic, fixed).

The one-call check on a GPU (the suite's failures at the paper's resolution):
  python3 benches/stability/finer.py target/release/splatter /tmp/gpu --scale 0.3 \
      --frames 4 scenes/pumpkin.json scenes/dragonfruit.json
  and the same with --p2g atomic, then --p2g gather.
Standard library only.
"""
import glob
import json
import os
import re
import subprocess
import sys
import time


def scaled(value, scale):
    """The scene with its dx and every spacing times `scale`."""
    if isinstance(value, dict):
        return {k: (v * scale if k in ("dx", "spacing") and isinstance(v, (int, float))
                    else scaled(v, scale)) for k, v in value.items()}
    if isinstance(value, list):
        return [scaled(v, scale) for v in value]
    return value


def run_scene(splatter, scene, out, frames, quality, timeout, scale=None, p2g=None):
    name = os.path.splitext(os.path.basename(scene))[0]
    dest = os.path.join(out, name)
    if scale is not None:
        text = scaled(json.load(open(scene)), scale)
        # Written beside the output (no shipped scene loads files by a relative path).
        os.makedirs(out, exist_ok=True)
        scene = os.path.join(out, f"{name}_x{scale:g}.json")
        json.dump(text, open(scene, "w"))
        quality = "standard"
    cmd = [splatter, "render", scene, "--out", dest, "--frames", f"0..{frames}",
           "--quality", quality, "--width", "160", "--height", "120"]
    if p2g:
        cmd += ["--p2g", p2g]
    t = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        text, code = p.stderr + p.stdout, p.returncode
    except subprocess.TimeoutExpired as e:
        text = (e.stderr or b"").decode() if isinstance(e.stderr, bytes) else (e.stderr or "")
        code = "timeout"
    wall = time.time() - t
    row = {"scene": name, "exit": code, "wall_s": round(wall, 1)}
    m = re.search(r"simulation: (\d+) particles", text)
    row["particles"] = int(m.group(1)) if m else 0
    m = re.search(r"(\d+) steps per frame", text)
    row["first_steps"] = int(m.group(1)) if m else 0
    # A run of some of the scene's frames names its manifest after them.
    manifests = sorted(glob.glob(os.path.join(dest, "manifest*.json")))
    reached = -1
    if manifests:
        manifest = manifests[0]
        mf = json.load(open(manifest))
        done = sorted(int(f) for f in mf.get("frames", {}))
        reached = done[-1] if done else -1
        row["steps"] = [mf["frames"][str(f)].get("steps") for f in done
                        if mf["frames"][str(f)].get("steps")]
        # Frames run again at half the step (steps that inverted a particle, or NaN).
        row["halvings"] = sum(mf["frames"][str(f)].get("halvings", 0) for f in done)
        sim = [mf["frames"][str(f)]["simulate_ms"] for f in done if f > 0]
        row["s_per_frame"] = round(sum(sim) / len(sim) / 1e3, 2) if sim else None
    row["frames_reached"] = reached + 1
    err = [line for line in text.splitlines() if line.startswith("error")]
    row["error"] = err[-1][:300] if err else ""
    row["nan"] = bool(re.search(r"became NaN", row["error"]))
    row["escaped"] = bool(re.search(r"left the domain", row["error"]))
    row["blew_up"] = "blew up" in row["error"] or "an instability" in row["error"]
    return row


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        print(__doc__)
        sys.exit(2)
    splatter, out = args[0], args[1]
    frames, quality, timeout, scenes, scale, p2g = 2, "high", 900, [], None, None
    rest = args[2:]
    while rest:
        a = rest.pop(0)
        if a == "--frames":
            frames = int(rest.pop(0))
        elif a == "--quality":
            quality = rest.pop(0)
        elif a == "--scale":
            scale = float(rest.pop(0))
        elif a == "--p2g":
            p2g = rest.pop(0)
        elif a == "--timeout":
            timeout = float(rest.pop(0))
        else:
            scenes.append(a)
    if not scenes:
        scenes = sorted(glob.glob("scenes/*.json"))
    os.makedirs(out, exist_ok=True)
    rows = []
    for s in scenes:
        row = run_scene(splatter, s, out, frames, quality, timeout, scale, p2g)
        rows.append(row)
        print(json.dumps(row), file=sys.stderr, flush=True)
        json.dump(rows, open(os.path.join(out, "finer.json"), "w"), indent=1)
    print(f"| scene | particles | frames reached of {frames} | stopped | steps per frame | "
          "halvings | s/frame |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        why = ("NaN" if r["nan"] else "escaped" if r["escaped"] else
               "timeout" if r["exit"] == "timeout" else r["error"][:60] if r["error"] else "")
        if r["blew_up"]:
            why += " (blow-up)"
        steps = ", ".join(str(s) for s in r.get("steps", [])) or str(r.get("first_steps") or "")
        print(f"| {r['scene']} | {r['particles']} | {r['frames_reached']} | {why or 'no'} | "
              f"{steps} | {r.get('halvings', 0)} | {r.get('s_per_frame')} |")


if __name__ == "__main__":
    main()
