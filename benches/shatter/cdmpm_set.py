#!/usr/bin/env python3
"""CD-MPM's own watermelon set on our flat drop (docs/notes/brittle.md, "CD-MPM's watermelon set").

CD-MPM's watermelon smash (penn-graphics-research/ziran2019, Projects/mpm/MpmInit3D.h,
test 1) is NACC on the Borden neo-Hookean with: rind E 2000, nu 0.4, alpha0 ln 0.99, beta 2,
xi 3, friction angle 45 deg; flesh E 1000, nu 0.35, alpha0 ln 0.97, beta 1, xi 3, 45 deg;
density 2, dropped at 6.5 m/s under g 3, FLIP/PIC 0.99, CFL 0.6, a slip ground with
friction 0.2. Each variant is scenes/watermelon_drop_nacc.json's geometry (the procedural
watermelon: its rind and white rind take CD-MPM's rind, its flesh and seeds CD-MPM's flesh)
with that set, at one grid spacing, with one velocity field per node or two, the whole
fruit or the quarter between two slip planes through its centre (as fine.py).

Usage: python3 benches/shatter/cdmpm_set.py OUT_DIR [FRUIT:DX:FIELDS ...]
  (default: whole:0.015:one whole:0.015:two quarter:0.0075:one quarter:0.0075:two), then
    splatter render OUT_DIR/NAME.json --out OUT_DIR/NAME --fragments [--export-particles DIR]
Standard library only.
"""
import copy
import json
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from fine import cut_to_quarter  # noqa: E402

BASE = os.path.join(HERE, "..", "..", "scenes", "watermelon_drop_nacc.json")
DEFAULT = ["whole:0.015:one", "whole:0.015:two", "quarter:0.0075:one", "quarter:0.0075:two"]


def nacc(e, nu, jp, beta):
    return {"model": "nacc", "E": e, "nu": nu, "density": 2, "alpha0": math.log(jp),
            "beta": beta, "xi": 3, "friction_angle_deg": 45, "return_mapping": "continuous"}


RIND = nacc(2000, 0.4, 0.99, 2)
FLESH = nacc(1000, 0.35, 0.97, 1)


def variant(base, fruit, dx, fields):
    s = copy.deepcopy(base)
    s["description"] = (f"CD-MPM's watermelon set on the flat drop, dx {dx}, {fruit} fruit, "
                        f"{fields} field(s) (benches/shatter/cdmpm_set.py)")
    melon = next(o for o in s["objects"] if o.get("name") == "watermelon")
    melon["physics"]["material"] = copy.deepcopy(FLESH)
    for r in melon["physics"]["regions"]:
        r["material"] = copy.deepcopy(RIND if r["label"] in ("rind", "white_rind") else FLESH)
    melon["physics"]["velocity"] = [0, 0, -6.5]
    sim = s["simulation"]
    sim["dx"] = dx
    sim["gravity"] = [0, 0, -3]
    sim["transfer"] = {"flip": 0.99}
    sim["cfl"] = 0.6
    sim["ground"]["friction"] = 0.2
    for c in sim["colliders"]:
        c["friction"] = 0.2
    s["output"]["frames"] = 12
    if fields == "two":
        sim["separation"] = "damage_gradient"
    if fruit == "quarter":
        cut_to_quarter(s)
    return s


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    base = json.load(open(BASE))
    for spec in sys.argv[2:] or DEFAULT:
        fruit, dx, fields = spec.split(":")
        path = os.path.join(out, f"cdmpm_{fruit}_{dx}_{fields}.json")
        with open(path, "w") as f:
            json.dump(variant(base, fruit, float(dx), fields), f, indent=1)
        print(path)


if __name__ == "__main__":
    main()
