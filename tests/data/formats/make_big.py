#!/usr/bin/env python3
"""Tile a float-only binary little-endian 3DGS PLY into a 3x3 grid: ~1M Gaussians.

Usage: make_big.py INPUT.ply OUTPUT.ply [--grid 3] [--spacing S]

For plant.ply (113,648 Gaussians, up is -y) this writes 9 translated copies in the x-z
plane (1,022,832 Gaussians), for read-speed benchmarks.  Copy (i, j) for i, j in
0..grid-1 (j fastest) is the whole source with x += (i - (grid-1)/2) * S and
z += (j - (grid-1)/2) * S, S = 1.2 * the larger of the x and z extents unless given
(plant: 0.7317).  Every copy but the first, (0, 0), is also jittered so that the nine
copies are not byte-identical (a zstd- or gzip-compressed format would otherwise find
the repeats and come out unrealistically small): each value of each row gets
+ amp * u, u uniform in [-1, 1) from random.Random(tile index) (whose random() sequence
Python guarantees across versions), amp = 0.0005 for x y z, 0.02 for every other
property except nx ny nz (left as they are).  Deterministic; standard library only.
"""
import argparse
import array
import random
import sys

POS_AMP, AMP = 0.0005, 0.02
SKIP = ("nx", "ny", "nz")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--grid", type=int, default=3)
    ap.add_argument("--spacing", type=float, default=0.0)
    a = ap.parse_args()

    data = open(a.input, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    lines = data[:end].decode("ascii").split("\n")
    if "format binary_little_endian 1.0" not in lines:
        sys.exit("need a binary_little_endian PLY")
    props, n = [], None
    for ln in lines:
        p = ln.split()
        if p[:2] == ["element", "vertex"]:
            n = int(p[2])
        elif p and p[0] == "element":
            sys.exit("need exactly one element, 'vertex'")
        elif p and p[0] == "property":
            if p[1] not in ("float", "float32"):
                sys.exit("only float properties are supported")
            props.append(p[2])
    w = len(props)
    src = array.array("f")
    src.frombytes(data[end:end + 4 * w * n])
    if sys.byteorder != "little":
        src.byteswap()
    ix, iz = props.index("x"), props.index("z")
    xs, zs = src[ix::w], src[iz::w]
    s = a.spacing or 1.2 * max(max(xs) - min(xs), max(zs) - min(zs))
    g = a.grid
    out_lines = [("element vertex %d" % (n * g * g)) if ln.startswith("element vertex ")
                 else ln for ln in lines]
    with open(a.output, "wb") as f:
        f.write("\n".join(out_lines).encode("ascii"))
        for i in range(g):
            for j in range(g):
                dx, dz = (i - (g - 1) / 2) * s, (j - (g - 1) / 2) * s
                tile = array.array("f", src)
                k = i * g + j
                if k:
                    rnd = random.Random(k).random
                    for c, name in enumerate(props):
                        if name in SKIP:
                            continue
                        amp = POS_AMP if name in ("x", "y", "z") else AMP
                        tile[c::w] = array.array(
                            "f", (v + amp * (2.0 * rnd() - 1.0) for v in tile[c::w]))
                tile[ix::w] = array.array("f", (v + dx for v in tile[ix::w]))
                tile[iz::w] = array.array("f", (v + dz for v in tile[iz::w]))
                if sys.byteorder != "little":
                    tile.byteswap()
                f.write(tile.tobytes())
    print("%s: %d Gaussians (%dx%d copies of %d, spacing %.4f)" % (a.output, n * g * g, g, g, n, s))


if __name__ == "__main__":
    main()
