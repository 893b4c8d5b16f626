#!/usr/bin/env python3
"""Compaction of snow particles from `splatter render --export-particles` PLYs.

usage: compaction.py FRAME.ply [FRAME.ply ...]

For each file and object: the plastic density ratio 1/Jp = exp(-log_jp) of its particles
(median, largest; the share compacted, Jp < 1, and their mean; the shares compacted by
more than 5% and 20%, and the share dilated, torn apart, by more than 5%). The
total density ratio is 1/(J_E Jp): snow keeps the elastic singular values in
[1 - critical_compression, 1 + critical_stretch], so J_E lies in [0.927, 1.023] with the
default parameters and 1/Jp is the total to within that band.
"""
import sys

import numpy as np

TYPES = {"float": "<f4", "int": "<i4", "uint": "<u4", "double": "<f8", "uchar": "u1"}


def read(path):
    with open(path, "rb") as f:
        names, dtypes, n = [], [], 0
        while True:
            line = f.readline().decode("ascii").strip()
            if line.startswith("element vertex"):
                n = int(line.split()[2])
            elif line.startswith("property"):
                _, t, name = line.split()
                names.append(name)
                dtypes.append(TYPES[t])
            elif line == "end_header":
                break
        return np.frombuffer(f.read(), dtype=list(zip(names, dtypes)), count=n)


for path in sys.argv[1:]:
    v = read(path)
    for obj in np.unique(v["object"]):
        s = v[v["object"] == obj]
        a = s["log_jp"].astype(np.float64)
        m = s["mass"].astype(np.float64)
        ratio = np.exp(-a)
        packed = ratio > 1.0
        print(
            f"{path} object {obj}: {len(s)} particles; plastic density ratio 1/Jp: "
            f"median {np.median(ratio):.3f}, max {ratio.max():.3f}; compacted "
            f"(Jp < 1) {np.mean(packed):.3f} of the particles, their mean "
            f"{ratio[packed].mean() if packed.any() else 1.0:.3f}; compacted >5% "
            f"{np.mean(ratio > 1.05):.3f}, >20% {np.mean(ratio > 1.2):.3f}; "
            f"dilated (Jp > 1.05) {np.mean(ratio < 1 / 1.05):.3f}"
        )
