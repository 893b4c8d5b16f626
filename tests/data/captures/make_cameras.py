#!/usr/bin/env python3
"""Cameras for the plant as a phone video round it would pose them (INRIA 3DGS cameras.json).

The plant's author does not distribute its training cameras, so these are placed by hand in
the capture's own frame, round its known up (-y, see README.md): 24 views over 330 degrees
of azimuth (a walk round the pot that does not close), 1.2-1.4 from the centre, pitched
15-40 degrees down at it, rolled up to 4 degrees either way and aimed within 3 cm of the
centre (a hand-held phone). Each camera's image up is the world's up tilted by its pitch
and roll, as in a real capture. Deterministic (fixed seed); standard library only.

Usage: make_cameras.py OUTPUT.json
"""
import json
import math
import random
import sys

UP = (0.0, -1.0, 0.0)
CENTRE = (0.0026, 0.0165, 0.0075)  # the centre of plant_14k.spz's robust bounds
# Two directions across UP, completing a right-handed frame (E1 x E2 = UP).
E1 = (1.0, 0.0, 0.0)
E2 = (0.0, 0.0, -1.0)


def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def scale(s, a):
    return tuple(s * x for x in a)


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def normalize(a):
    n = math.sqrt(sum(x * x for x in a))
    return scale(1.0 / n, a)


def camera(i, rng):
    azimuth = math.radians(330.0 * i / 23)
    pitch = math.radians(rng.uniform(15.0, 40.0))
    roll = math.radians(rng.uniform(-4.0, 4.0))
    distance = rng.uniform(1.2, 1.4)
    radial = add(scale(math.cos(azimuth), E1), scale(math.sin(azimuth), E2))
    eye = add(CENTRE, add(scale(distance * math.cos(pitch), radial), scale(distance * math.sin(pitch), UP)))
    target = add(CENTRE, tuple(rng.uniform(-0.03, 0.03) for _ in range(3)))
    # OpenCV axes: z forward, x right, y down the image.
    z = normalize(sub(target, eye))
    x = normalize(cross(z, UP))
    y = cross(z, x)
    c, s = math.cos(roll), math.sin(roll)
    x, y = add(scale(c, x), scale(s, y)), add(scale(-s, x), scale(c, y))
    rows = [[x[k], y[k], z[k]] for k in range(3)]  # camera-to-world, by rows
    return {
        "id": i,
        "img_name": "frame_%05d" % i,
        "width": 1920,
        "height": 1080,
        "position": [round(v, 6) for v in eye],
        "rotation": [[round(v, 6) for v in row] for row in rows],
        "fx": 1500.0,
        "fy": 1500.0,
    }


def main():
    rng = random.Random(7)
    cams = [camera(i, rng) for i in range(24)]
    with open(sys.argv[1], "w") as f:
        json.dump(cams, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
