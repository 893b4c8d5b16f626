#!/usr/bin/env python3
"""The peer of `splatter bench sim`: the same MPM case stepped by Taichi on the CPU.

What is the same as `splatter bench sim`'s fixed-corotated case (`SimCase` in
src/bench.rs): the particle lattice (a cube of n³ particles at spacing dx/2, 8 per cell,
density 2), the unit domain of `cells`³ cells with quadratic B-spline weights, MLS-MPM/APIC
transfers, the fixed-corotated material with the same E and ν, the step Δt, gravity along
−y, a sticky ground and separating walls. What is Taichi's own: a dense grid cleared every
step (the usual Taichi layout) and f32 throughout.

    pip install taichi==1.7.4
    python3 benches/peers/taichi_mpm.py --per-axis 27 --cells 64 --dt 1e-4 --steps 20

`splatter-lab peer taichi` runs this script with the case's numbers and prints the
ratio. The last line printed is `ms/step: <value>`.
"""

import argparse
import time

import taichi as ti

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--per-axis", type=int, default=27, help="particles per axis of the cube")
ap.add_argument("--cells", type=int, default=64, help="grid cells per axis (unit domain)")
ap.add_argument("--lo", type=float, nargs=3, default=None, help="the cube's low corner")
ap.add_argument("--dt", type=float, default=1e-4)
ap.add_argument("--steps", type=int, default=20)
ap.add_argument("--E", type=float, default=2000.0)
ap.add_argument("--nu", type=float, default=0.4)
ap.add_argument("--density", type=float, default=2.0)
args = ap.parse_args()

ti.init(arch=ti.cpu, default_fp=ti.f32, offline_cache=True, log_level=ti.WARN)

n_grid = args.cells
dx = 1.0 / n_grid
inv_dx = float(n_grid)
spacing = dx / 2
side = args.per_axis * spacing
lo = args.lo or [0.5 - side / 2, 0.1, 0.5 - side / 2]
n = args.per_axis ** 3
dt = args.dt
vol = spacing ** 3
mass = args.density * vol
E, nu = args.E, args.nu
mu = E / (2 * (1 + nu))
la = E * nu / ((1 + nu) * (1 - 2 * nu))
# Nodes within this many cells of a face get the wall's condition.
bound = 2

x = ti.Vector.field(3, float, n)
v = ti.Vector.field(3, float, n)
C = ti.Matrix.field(3, 3, float, n)
F = ti.Matrix.field(3, 3, float, n)
grid_v = ti.Vector.field(3, float, (n_grid + 1,) * 3)
grid_m = ti.field(float, (n_grid + 1,) * 3)


@ti.kernel
def init(lx: float, ly: float, lz: float):
    for p in x:
        i = p % args.per_axis
        j = (p // args.per_axis) % args.per_axis
        k = p // (args.per_axis * args.per_axis)
        x[p] = ti.Vector([lx, ly, lz]) + (ti.Vector([i, j, k]) + 0.5) * spacing
        v[p] = ti.Vector.zero(float, 3)
        C[p] = ti.Matrix.zero(float, 3, 3)
        F[p] = ti.Matrix.identity(float, 3)


@ti.kernel
def substep():
    for I in ti.grouped(grid_m):
        grid_v[I] = ti.Vector.zero(float, 3)
        grid_m[I] = 0.0
    # P2G: the fixed-corotated Kirchhoff stress τ = 2μ (F − R) Fᵀ + λ (J − 1) J I.
    for p in x:
        base = int(x[p] * inv_dx - 0.5)
        fx = x[p] * inv_dx - base
        w = [0.5 * (1.5 - fx) ** 2, 0.75 - (fx - 1) ** 2, 0.5 * (fx - 0.5) ** 2]
        f = (ti.Matrix.identity(float, 3) + dt * C[p]) @ F[p]
        F[p] = f
        U, sig, V = ti.svd(f)
        r = U @ V.transpose()
        J = f.determinant()
        tau = 2 * mu * (f - r) @ f.transpose() + ti.Matrix.identity(float, 3) * la * J * (J - 1)
        stress = -dt * vol * 4 * inv_dx * inv_dx * tau
        affine = stress + mass * C[p]
        for i, j, k in ti.static(ti.ndrange(3, 3, 3)):
            offset = ti.Vector([i, j, k])
            dpos = (offset - fx) * dx
            weight = w[i][0] * w[j][1] * w[k][2]
            grid_v[base + offset] += weight * (mass * v[p] + affine @ dpos)
            grid_m[base + offset] += weight * mass
    # Grid: momentum → velocity, gravity, walls (sticky ground, separating elsewhere).
    for I in ti.grouped(grid_m):
        if grid_m[I] > 0:
            vel = grid_v[I] / grid_m[I]
            vel[1] -= dt * 9.8
            for d in ti.static(range(3)):
                if I[d] < bound and vel[d] < 0:
                    vel[d] = 0
                if I[d] > n_grid - bound and vel[d] > 0:
                    vel[d] = 0
            if I[1] < bound:
                vel = ti.Vector.zero(float, 3)
            grid_v[I] = vel
    # G2P: APIC velocity and affine matrix, then advection.
    for p in x:
        base = int(x[p] * inv_dx - 0.5)
        fx = x[p] * inv_dx - base
        w = [0.5 * (1.5 - fx) ** 2, 0.75 - (fx - 1.0) ** 2, 0.5 * (fx - 0.5) ** 2]
        new_v = ti.Vector.zero(float, 3)
        new_c = ti.Matrix.zero(float, 3, 3)
        for i, j, k in ti.static(ti.ndrange(3, 3, 3)):
            offset = ti.Vector([i, j, k])
            dpos = (offset - fx) * dx
            g = grid_v[base + offset]
            weight = w[i][0] * w[j][1] * w[k][2]
            new_v += weight * g
            new_c += 4 * inv_dx * inv_dx * weight * g.outer_product(dpos)
        v[p] = new_v
        C[p] = new_c
        x[p] += dt * new_v


init(*lo)
# Two warm-up steps: the kernels are compiled on their first call.
substep()
substep()
ti.sync()
start = time.perf_counter()
for _ in range(args.steps):
    substep()
ti.sync()
ms = (time.perf_counter() - start) * 1e3 / args.steps
version = ".".join(str(v) for v in ti.__version__)
print(f"taichi {version}, cpu, {n} particles, {n_grid}³ grid, fixed corotated, dt {dt:g}, {args.steps} steps")
print(f"ms/step: {ms:.3f}")
