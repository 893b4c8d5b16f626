#!/usr/bin/env python3
"""Scenes for the watermelon drop at a GPU's resolutions (docs/notes/watermelon-nacc.md, "On a GPU").

Each scene is scenes/watermelon_drop_nacc.json (Table A1's materials as read, rho 2, 8 m/s onto a
flat table with friction 0.5, continuous return mapping) at one grid spacing, with one
velocity field per node or two ("separation": "damage_gradient", method section 4.9), for
the whole fruit or one quarter of it between two slip planes through its centre (the cut
of `splatter-lab accuracy --shatter-quarter`, splatter_lab::shatter::cut_to_quarter). The
fruit's Gaussians stay as shipped (spacing 0.005): the particles follow dx, the picture
does not need to.

Usage: python3 benches/shatter/fine.py OUT_DIR [FRUIT:DX:FIELDS[:MAPPING] ...]
  FRUIT is quarter or whole, DX the grid spacing in metres, FIELDS one or two, MAPPING
  continuous (the default, as shipped) or center; the default list is the one run on the
  GPU. Then, for each OUT_DIR/NAME.json,
    splatter render OUT_DIR/NAME.json --out OUT_DIR/NAME --fragments --width 360 --height 240
and read OUT_DIR/NAME/fragments.csv (pieces, largest_share, damaged_share per frame).
Standard library only.
"""
import copy
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SHIPPED = os.path.join(HERE, "..", "..", "scenes", "watermelon_drop_nacc.json")
DEFAULT = ["quarter:0.004:one", "quarter:0.004:two", "quarter:0.003:one",
           "quarter:0.003:two", "quarter:0.003:one:center", "whole:0.005:two",
           "whole:0.003:one"]


def cut_to_quarter(scene):
    """The quarter with x and y above the fruit's centre, between slip planes through it."""
    sim = scene["simulation"]
    fruit = next(o for o in scene["objects"] if o.get("name") == "watermelon")
    c = fruit["transform"]["translate"]
    lo, hi = sim["domain"]["lo"], sim["domain"]["hi"]
    fruit["physics"]["select"] = {"box": {"lo": [c[0], c[1], lo[2]], "hi": hi}}
    sim.setdefault("colliders", []).extend(
        {"point": c, "normal": n, "kind": "slip", "friction": 0.0}
        for n in ([1, 0, 0], [0, 1, 0]))


def set_mapping(node, mapping):
    """Every NACC material under `node` gets `mapping`."""
    if isinstance(node, dict):
        if node.get("model") == "nacc":
            node["return_mapping"] = mapping
        for x in node.values():
            set_mapping(x, mapping)
    elif isinstance(node, list):
        for x in node:
            set_mapping(x, mapping)


def variant(base, fruit, dx, fields, mapping):
    s = copy.deepcopy(base)
    s["description"] = (
        f"scenes/watermelon_drop_nacc.json at dx {dx}, {fruit} fruit, {fields} velocity "
        f"field(s) per node, {mapping} return mapping (benches/shatter/fine.py)")
    set_mapping(s["objects"], mapping)
    s["simulation"]["dx"] = dx
    if fields == "two":
        s["simulation"]["separation"] = "damage_gradient"
    if fruit == "quarter":
        cut_to_quarter(s)
    return s


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    base = json.load(open(SHIPPED))
    for spec in sys.argv[2:] or DEFAULT:
        fruit, dx, fields, mapping = (spec.split(":") + ["continuous"])[:4]
        if (fruit not in ("quarter", "whole") or fields not in ("one", "two")
                or mapping not in ("continuous", "center")):
            sys.exit(f"{spec}: expected FRUIT:DX:FIELDS[:MAPPING] with quarter|whole, "
                     "one|two and continuous|center")
        suffix = "" if mapping == "continuous" else f"_{mapping}"
        path = os.path.join(out, f"{fruit}_{dx}_{fields}{suffix}.json")
        with open(path, "w") as f:
            json.dump(variant(base, fruit, float(dx), fields, mapping), f, indent=1)
        print(path)


if __name__ == "__main__":
    main()
