#!/usr/bin/env python3
"""Give every Gaussian of the plant capture a segment, as a segmentation tool would.

usage: python3 make_segments.py plant_14k.ply plant_14k_segmented.ply

The input is a 3DGS PLY with float properties only (`splatter convert plant_14k.spz
plant_14k.ply`); the output is the same rows with an `int segment` property appended:
1 for the pot, 2 for the plant. The rule stands in for a segmentation model: a Gaussian is
the pot's when it lies below the pot's rim (y > 0.14 in the capture's own frame, whose up
is -y) and is not green (its DC colour's green does not lead red and blue by 0.05); the
rest, leaves hanging over the rim included, is the plant's. Standard library only.
"""
import struct
import sys

RIM_Y = 0.14
POT, PLANT = 1, 2


def main(src, dst):
    data = open(src, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    props = [line.split()[-1] for line in header if line.startswith("property")]
    if any(line.split()[1] != "float" for line in header if line.startswith("property")):
        sys.exit(f"{src}: expected float properties only")
    count = int(next(l for l in header if l.startswith("element vertex")).split()[-1])
    row = struct.Struct("<" + "f" * len(props))
    y, r, g, b = (props.index(k) for k in ("y", "f_dc_0", "f_dc_1", "f_dc_2"))
    out_header = [l for l in header if l != "end_header"]
    out_header += ["property int segment", "end_header"]
    body = bytearray()
    pots = 0
    for i in range(count):
        raw = data[end + i * row.size : end + (i + 1) * row.size]
        v = row.unpack(raw)
        green = v[g] > v[r] + 0.05 and v[g] > v[b] + 0.05
        segment = POT if v[y] > RIM_Y and not green else PLANT
        pots += segment == POT
        body += raw + struct.pack("<i", segment)
    with open(dst, "wb") as f:
        f.write(("\n".join(out_header) + "\n").encode("ascii"))
        f.write(body)
    print(f"{dst}: {count} Gaussians, {pots} pot (segment {POT}), {count - pots} plant (segment {PLANT})")


if __name__ == "__main__":
    main(*sys.argv[1:3])
