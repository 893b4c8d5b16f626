#!/usr/bin/env python3
"""Read a depth pass (`render --passes depth`) with OpenEXR's own Python bindings, an
independent reader, and compare it with the values splatter rendered, dumped as raw
little-endian f32 (the `depth` of `render::PassImages`, row-major).

usage: python3 read_depth.py OUT/depth/frame_00000.exr [RAW.f32]

Prints the channels, the size, the finite range and the count of +inf pixels; with RAW,
the largest difference (0 expected: the file is lossless). Needs `pip install OpenEXR`
(and numpy); not part of CI.
"""
import struct
import sys

import OpenEXR


def main(path, raw=None):
    with OpenEXR.File(path) as f:
        part = f.parts[0]
        names = list(part.channels.keys())
        z = part.channels["Z"].pixels
    h, w = z.shape
    flat = [float(v) for v in z.reshape(-1)]
    finite = [v for v in flat if v != float("inf")]
    print(f"{path}: channels {names}, {w}x{h}, finite {min(finite):.6f} .. {max(finite):.6f}, "
          f"{len(flat) - len(finite)} at +inf")
    if raw:
        data = open(raw, "rb").read()
        ours = struct.unpack(f"<{len(data) // 4}f", data)
        assert len(ours) == len(flat), (len(ours), len(flat))
        worst = max(0.0 if a == b else abs(a - b) for a, b in zip(ours, flat))
        print(f"against {raw}: largest difference {worst}")
        sys.exit(0 if worst == 0.0 else 1)


if __name__ == "__main__":
    main(*sys.argv[1:3])
