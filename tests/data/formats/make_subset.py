#!/usr/bin/env python3
"""Deterministic subset of a binary little-endian 3DGS PLY: keep every k-th Gaussian.

Usage: make_subset.py INPUT.ply OUTPUT.ply [--target N | --every K]
       make_subset.py INPUT.splat OUTPUT.splat [--target N | --every K]

Records are copied byte for byte (no float round trip), so the subset holds exactly
the values of the source rows 0, K, 2K, ...  The header is copied unchanged except for
the `element vertex` count.  An antimatter15 `.splat` (no header, 32-byte records) is
cut the same way.  Default: K = max(1, n // 4000) (donut: 45,624 // 4000 = 11, which
keeps 4,148 Gaussians).  Standard library only.
"""
import argparse
import sys

SIZES = {
    "char": 1, "int8": 1, "uchar": 1, "uint8": 1,
    "short": 2, "int16": 2, "ushort": 2, "uint16": 2,
    "int": 4, "int32": 4, "uint": 4, "uint32": 4,
    "float": 4, "float32": 4, "double": 8, "float64": 8,
}


def read_header(data):
    end = data.find(b"end_header\n")
    if end < 0:
        sys.exit("no end_header")
    end += len(b"end_header\n")
    lines = data[:end].decode("ascii").split("\n")
    if lines[0] != "ply" or "format binary_little_endian 1.0" not in lines:
        sys.exit("need a binary_little_endian PLY")
    elements = []  # (name, count, stride)
    for ln in lines:
        parts = ln.split()
        if not parts:
            continue
        if parts[0] == "element":
            elements.append([parts[1], int(parts[2]), 0])
        elif parts[0] == "property":
            if parts[1] == "list":
                sys.exit("list properties are not supported")
            elements[-1][2] += SIZES[parts[1]]
    if not elements or elements[0][0] != "vertex" or len(elements) != 1:
        sys.exit("need exactly one element, 'vertex'")
    return lines, end, elements[0][1], elements[0][2]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--target", type=int, default=4000,
                    help="aim for about this many Gaussians (K = n // target)")
    ap.add_argument("--every", type=int, default=0, help="keep every K-th Gaussian")
    a = ap.parse_args()

    with open(a.input, "rb") as f:
        data = f.read()
    if a.input.endswith(".splat"):
        lines, body, n, stride = None, 0, len(data) // 32, 32
        if len(data) % 32:
            sys.exit("a .splat holds whole 32-byte records")
    else:
        lines, body, n, stride = read_header(data)
    if len(data) < body + n * stride:
        sys.exit("file is shorter than its header says")
    k = a.every if a.every > 0 else max(1, n // a.target)
    keep = range(0, n, k)
    with open(a.output, "wb") as f:
        if lines is not None:
            out_lines = [
                ("element vertex %d" % len(keep)) if ln.startswith("element vertex ") else ln
                for ln in lines
            ]
            f.write("\n".join(out_lines).encode("ascii"))
        for i in keep:
            o = body + i * stride
            f.write(data[o:o + stride])
    print("%s: %d of %d Gaussians (every %d-th), %d bytes per Gaussian"
          % (a.output, len(keep), n, k, stride))


if __name__ == "__main__":
    main()
