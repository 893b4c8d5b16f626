#!/usr/bin/env python3
"""Scenes for the watermelon's ingredient table (docs/notes/watermelon-nacc.md, "Ingredients").

Each variant is scenes/watermelon_drop_nacc.json with the ingredients that differ from the
official GaussianFluent release's watermelon switched to the release's values, cut to 6
frames (the impact and the first rebound):

  A_ours                   the shipped scene (APIC, separating table with friction 0.5,
                           Table A1's rind / flesh / seeds as we read them, rho 2, 8 m/s)
  B_flip                   A with the release's transfer: a FLIP/PIC blend of 0.7
  C_sticky                 A with the release's floor: the table and ground sticky
  D_release_all_but_flip   the release's floor, materials (one NACC for rind and flesh:
                           E 2000, nu 0.38, xi 3, beta 1, M 1.85 from 45 degrees; seeds
                           beta 3e9; rho 1) and drop (g -15, 7.5 m/s at impact)
  E_release_all            D with the FLIP/PIC blend 0.7
  F_release_all_dx0075     E at dx 0.0075 (twice as many cells across the fruit)

Usage: python3 benches/shatter/ingredients.py OUT_DIR, then for each OUT_DIR/V.json
    splatter render OUT_DIR/V.json --out OUT_DIR/out_V --fragments --width 64 --height 48
and read OUT_DIR/out_V/fragments.csv (pieces, largest_share, damaged_share per frame).
Standard library only.
"""
import copy
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SHIPPED = os.path.join(HERE, "..", "..", "scenes", "watermelon_drop_nacc.json")


def nacc(e, beta, rho, xi, m):
    return {"model": "nacc", "E": e, "nu": 0.38, "density": rho, "alpha0": -0.04,
            "beta": beta, "xi": xi, "M": m, "return_mapping": "continuous"}


def variant(base, flip=False, sticky=False, release_mat=False, release_drop=False, dx=None):
    s = copy.deepcopy(base)
    s.pop("description", None)
    s["output"]["frames"] = 6
    sim = s["simulation"]
    fruit = next(o for o in s["objects"] if o.get("name") == "watermelon")
    if flip:
        sim["transfer"] = {"flip": 0.7}
    if sticky:
        sim["ground"] = {"kind": "sticky"}
        for c in sim["colliders"]:
            c["kind"] = "sticky"
    if release_mat:
        body = nacc(2000, 1.0, 1, 3, 1.85)
        fruit["physics"]["material"] = body
        for r in fruit["physics"]["regions"]:
            r["material"] = nacc(2000, 3e9, 1, 3, 1.85) if r["label"] == "seeds" else body
    if release_drop:
        sim["gravity"] = [0, 0, -15]
        fruit["physics"]["velocity"] = [0, 0, -7.5]
    if dx is not None:
        # The procedural fruit is drawn at a third of the grid spacing, as shipped.
        fruit["procedural"]["spacing"] *= dx / sim["dx"]
        sim["dx"] = dx
    return s


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    base = json.load(open(SHIPPED))
    release = dict(sticky=True, release_mat=True, release_drop=True)
    variants = {
        "A_ours": variant(base),
        "B_flip": variant(base, flip=True),
        "C_sticky": variant(base, sticky=True),
        "D_release_all_but_flip": variant(base, **release),
        "E_release_all": variant(base, flip=True, **release),
        "F_release_all_dx0075": variant(base, flip=True, dx=0.0075, **release),
    }
    for name, scene in variants.items():
        path = os.path.join(out, name + ".json")
        with open(path, "w") as f:
            json.dump(scene, f, indent=1)
        print(path)


if __name__ == "__main__":
    main()
