#!/usr/bin/env python3
"""The pieces a render would show with GaussianFluent's render filter (docs/notes/brittle.md, "What the release's renderer hides").

GaussianFluent's release hides broken material when it renders its watermelon: every
particle whose particle_Jp (its NACC alpha, log Jp, starting at -0.04) exceeds 0.4 gets
opacity zero (gs_simulation/watermelon/gs_simulation_watermelon.py, lines 532-534 at commit
6a4732c of HB-pencil-zero/GaussianFluent). This reads our particle files
(`splatter render SCENE --export-particles DIR`: binary PLY, `log_jp` is alpha for NACC),
drops the particles with log_jp above the threshold, and counts the pieces of the rest as
`splatter fragments` does (single linkage at the file's dx; a piece holds >= 1% of the
object's particles, counted against all of them, hidden ones included).

Usage: python3 benches/shatter/release_filter.py PARTICLES.ply [THRESHOLD]
Standard library only.
"""
import math
import struct
import sys
from collections import defaultdict


def read(path):
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline().decode("ascii").strip()
            header.append(line)
            if line == "end_header":
                break
        count, names, dx = 0, [], None
        for line in header:
            parts = line.split()
            if parts[:2] == ["element", "vertex"]:
                count = int(parts[2])
            elif parts[0] == "property":
                names.append((parts[1], parts[2]))
            elif parts[:2] == ["comment", "dx"]:
                dx = float(parts[2])
        fmt = "<" + "".join("f" if t == "float" else "i" for t, _ in names)
        size = struct.calcsize(fmt)
        data = f.read(size * count)
    rows = [struct.unpack_from(fmt, data, i * size) for i in range(count)]
    cols = [n for _, n in names]
    return [dict(zip(cols, r)) for r in rows], dx


def pieces(points, link, total):
    parent = list(range(len(points)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    cells = defaultdict(list)
    for i, p in enumerate(points):
        cells[tuple(math.floor(c / link) for c in p)].append(i)
    for c, members in cells.items():
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    other = cells.get((c[0] + dx, c[1] + dy, c[2] + dz))
                    if not other:
                        continue
                    for i in members:
                        for j in other:
                            if j > i and sum((a - b) ** 2 for a, b in zip(points[i], points[j])) < link * link:
                                ri, rj = find(i), find(j)
                                if ri != rj:
                                    parent[max(ri, rj)] = min(ri, rj)
    sizes = defaultdict(int)
    for i in range(len(points)):
        sizes[find(i)] += 1
    sizes = sorted(sizes.values(), reverse=True)
    big = [s for s in sizes if s >= 0.01 * total]
    return len(big), (big[0] / total if big else 0.0), len(sizes)


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    threshold = float(sys.argv[2]) if len(sys.argv) > 2 else 0.4
    rows, dx = read(sys.argv[1])
    for obj in sorted({r["object"] for r in rows}):
        mine = [r for r in rows if r["object"] == obj]
        kept = [(r["x"], r["y"], r["z"]) for r in mine
                if not (r["log_jp"] == r["log_jp"] and r["log_jp"] > threshold)]
        n, largest, frags = pieces([(r["x"], r["y"], r["z"]) for r in mine], dx, len(mine))
        nf, largest_f, frags_f = pieces(kept, dx, len(mine))
        print(f"object {obj}: {len(mine)} particles; all: {n} pieces >= 1%, largest {largest:.1%}, "
              f"{frags} fragments; log_jp <= {threshold}: {len(kept)} kept ({len(kept) / len(mine):.1%}), "
              f"{nf} pieces >= 1%, largest {largest_f:.1%}, {frags_f} fragments")


if __name__ == "__main__":
    main()
