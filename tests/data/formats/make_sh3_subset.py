#!/usr/bin/env python3
"""A 300-Gaussian, SH-degree-3 PLY from donut_4k.ply, for the GLB fixture.

Usage: make_sh3_subset.py donut_4k.ply OUTPUT.ply

Keeps rows 0, 13, 26, ... (300 rows) of donut_4k.ply with their values as they are
(x y z f_dc_0..2 opacity scale_0..2 rot_0..3, float32), and adds the 45 rest
coefficients f_rest_0..44 that the donut lacks, from a formula the tests repeat:
f_rest_j of output row i = ((31 i + 17 j) mod 201 - 100) / 256 (exact in float32).
The rest coefficients are channel-major as in graphdeco's PLY: f_rest_j is channel
j // 15, coefficient 1 + j % 15.  Standard library only.
"""
import struct
import sys

EVERY, COUNT, REST = 13, 300, 45
FIELDS = ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity",
          "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]


def rest(i, j):
    return ((31 * i + 17 * j) % 201 - 100) / 256.0


def main():
    src, dst = sys.argv[1], sys.argv[2]
    data = open(src, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    names = [ln.split()[2] for ln in data[:end].decode().split("\n")
             if ln.startswith("property")]
    if names != FIELDS:
        sys.exit(f"unexpected properties {names}")
    stride = 4 * len(FIELDS)
    out_names = FIELDS[:6] + [f"f_rest_{j}" for j in range(REST)] + FIELDS[6:]
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {COUNT}"]
    header += [f"property float {n}" for n in out_names] + ["end_header", ""]
    body = bytearray()
    for i in range(COUNT):
        row = struct.unpack_from(f"<{len(FIELDS)}f", data, end + i * EVERY * stride)
        values = list(row[:6]) + [rest(i, j) for j in range(REST)] + list(row[6:])
        body += struct.pack(f"<{len(values)}f", *values)
    with open(dst, "wb") as f:
        f.write("\n".join(header).encode() + bytes(body))


if __name__ == "__main__":
    main()
