#!/usr/bin/env python3
"""The official GaussianFluent release's watermelon drop, run by the release's own Warp MPM
solver on the CPU, on our watermelon's particles (docs/notes/watermelon-nacc.md, "The release's solver
as a peer"). Not run by CI.

  python3 benches/peers/gaussianfluent_watermelon.py scene N OUT.json [elastic]
      Our scene of the release's setup at n_grid N: the fruit scaled so its largest extent
      is 1 and centred at (1, 1, 1) in a [0, 2]^3 domain, dx = 2/N, the release's material
      (one NACC, E 2000, nu 0.38, xi 3, beta 1, M 1.85, log Jp -0.04; our seed region beta
      3e9), density 1, g -15, v -6 m/s, FLIP/PIC 0.7 and its floor as it acts (see below).
      Render it with --export-particles DIR --fragments to get both the particles the peer
      starts from (DIR/frame_00000.ply) and our solver's run on the same work.

  python3 benches/peers/gaussianfluent_watermelon.py run SNAPSHOT PARTICLES.ply N FRAMES OUT_DIR [VARIANT]
      The release's solver (SNAPSHOT: a checkout of HB-pencil-zero/GaussianFluent; its
      mpm_solver_warp/ is copied to a temporary folder and patched there for warp-lang 1.x,
      nothing of it is kept here) on those particles, with the driver's settings
      (gs_simulation_watermelon.py: dt = 0.6 dx / c, 0.03 s frames, p2g2p with flip 0.7,
      a bounding box and the sticky plane at z = 0). Writes OUT_DIR/frame_NNNNN.ply in our
      particle format; count its pieces with `splatter fragments OUT_DIR/frame_*.ply`.
      VARIANT: one-line edits of the temporary copy, to find what decides the result:
        as_released         (default) as released, but for the guarded division below
        no_case3_hardening  its return mapping scales the deviatoric stress back onto the
                            yield surface at constant pressure (the elastic J does not
                            change) but still updates log Jp by log(J / J_fake), J_fake
                            from where the line from the ellipse's centre through the
                            trial stress meets it; this drops that update (the tips still
                            harden)
        unweighted_force    its FLIP P2G adds each node's stress impulse times the node's
                            weight, w_ip dt f_ip, where its own APIC P2G (and MLS-MPM)
                            adds dt f_ip; this removes the extra w_ip
        elastic             its `jelly` (fixed corotated, no plasticity) with the same E
                            and nu, against our scene's `scene N OUT.json elastic`
        elastic_unweighted_force  both of the last two

The release's floor: its sticky surface collider at z = 0 zeroes nodes with z < 0, of which
the grid has none, so the fruit lands on the bounding box's bottom padding (nodes below
3 dx lose their downward velocity and keep their tangential one): a frictionless,
separating floor at about 2-3 dx. Our scene uses a separating ground without friction.

The guarded division: the release's FLIP G2P divides each node's momentum by its mass; a
particle exactly half a cell from a node no other particle reaches makes that 0/0, the
particle NaN and the next P2G index the grid out of range (a segfault in warp's release
mode; WARP_MODE=debug reports it). A lattice fill hits it, so every variant guards that
division, which changes nothing where it was defined, and the run stops with a message if
a particle still leaves the grid.

Needs numpy and warp-lang 1.x (pip); no CUDA. torch and h5py, which the release imports at
module level but this path does not use, are replaced by empty stand-ins.
"""
import json
import os
import shutil
import sys
import tempfile
import time

import numpy as np

E, NU, RHO, XI, BETA, PHI, ALPHA0 = 2000.0, 0.38, 1.0, 3.0, 1.0, 45.0, -0.04
SEED_BETA, GRAVITY, V0, FLIP, FRAME_DT, CFL = 3e9, -15.0, -6.0, 0.7, 0.03, 0.6
# Our procedural watermelon (scale 1) is 0.296 across at its widest and centred on its
# origin; the release scales the fruit to extent 1.
FRUIT_EXTENT = 0.296
SEED_MATERIAL = 3  # the seeds region's material index in the scene below


def read_particles(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    props, n = [], 0
    for line in data[:end].decode().splitlines():
        if line.startswith("element vertex"):
            n = int(line.split()[2])
        if line.startswith("property"):
            kind, name = line.split()[1:3]
            props.append((name, {"float": "<f4", "int": "<i4"}[kind]))
    return np.frombuffer(data[end:], dtype=np.dtype(props), count=n)


def write_particles(path, x, v, log_jp, dx, frame):
    n = len(x)
    rec = np.zeros(n, dtype=[(k, "<f4") for k in ("x", "y", "z", "vx", "vy", "vz", "log_jp")])
    for i, k in enumerate("xyz"):
        rec[k] = x[:, i]
        rec["v" + k] = v[:, i]
    rec["log_jp"] = log_jp
    head = "ply\nformat binary_little_endian 1.0\ncomment GaussianFluent release, frame %d\n" % frame
    head += "comment dx %e\nelement vertex %d\n" % (dx, n)
    head += "".join("property float %s\n" % k for k in rec.dtype.names) + "end_header\n"
    with open(path, "wb") as f:
        f.write(head.encode())
        f.write(rec.tobytes())


def nacc(beta):
    return {"model": "nacc", "E": E, "nu": NU, "density": RHO, "alpha0": ALPHA0, "beta": beta,
            "xi": XI, "M": 1.85, "return_mapping": "continuous"}


def scene(n_grid, out, variant="as_released"):
    dx = 2.0 / n_grid
    s = 1.0 / FRUIT_EXTENT
    body = nacc(BETA)
    seeds = nacc(SEED_BETA)
    if variant == "elastic":
        body = seeds = {"model": "fixed_corotated", "E": E, "nu": NU, "density": RHO}
    # Frames as the release's driver writes them: one per 0.03 s.
    doc = {
        "description": "The GaussianFluent release's watermelon drop in its own frame, at n_grid %d "
                       "(benches/peers/gaussianfluent_watermelon.py)." % n_grid,
        "output": {"width": 64, "height": 48, "frames": 7, "fps": round(1 / FRAME_DT, 6)},
        "camera": {"fov_y_deg": 40, "path": {"type": "orbit", "target": [1, 1, 0.5],
                                             "radius": 4, "height": 1.5}},
        "simulation": {"dx": dx, "cfl": CFL, "gravity": [0, 0, GRAVITY],
                       "domain": {"lo": [0, 0, 0], "hi": [2, 2, 2]},
                       "walls": {"kind": "separate"},
                       "ground": {"kind": "separate", "friction": 0.0},
                       "transfer": {"flip": FLIP}},
        "objects": [{
            "name": "watermelon",
            # Drawn at a third of the grid spacing, as our shipped drop is.
            "procedural": {"shape": "watermelon", "spacing": dx / 3 / s, "seed": 3},
            "transform": {"translate": [1, 1, 1], "scale": s},
            "physics": {"material": body, "fill": True, "velocity": [0, 0, V0],
                        "regions": [{"label": "rind", "material": body},
                                    {"label": "white_rind", "material": body},
                                    {"label": "seeds", "material": seeds}]}}],
    }
    with open(out, "w") as f:
        json.dump(doc, f, indent=1)


CASE3_HARDENING = "if hardeningOn > 0.5 and p0 > 1e-4 and p_trial < p0 - 1e-4"
# g2p_flip divides each node's momentum by its mass. A particle exactly half a cell from a
# node gives that node weight 0; if no other particle reaches it, its mass is 0 and the
# 0/0 makes the particle NaN (then the next P2G indexes the grid out of bounds: the
# segfault). Particles on a lattice, as a fill makes them, hit this; so the copy guards
# the division, which changes nothing where it was defined.
# Its FLIP P2G adds the stress impulse scaled by the node's weight (w_ip dt f_ip; its
# APIC P2G adds dt f_ip): variant `unweighted_force` removes that factor.
WEIGHTED_FORCE = "v_out_add = weight * dt * elastic_force"
OLD_V = "old_v = old_v + state.grid_v_in[ix, iy, iz] * weight  / state.grid_m[ix, iy, iz]"
OLD_V_GUARDED = ("old_v = old_v + state.grid_v_in[ix, iy, iz] * weight / "
                 "wp.max(state.grid_m[ix, iy, iz], 1.0e-30)")


VARIANTS = ("as_released", "no_case3_hardening", "unweighted_force", "elastic",
            "elastic_unweighted_force")


def patched_solver(snapshot, variant):
    """A private copy of the release's solver that imports under warp-lang 1.x on a CPU."""
    tmp = tempfile.mkdtemp(prefix="gf_solver_")
    src = os.path.join(snapshot, "mpm_solver_warp")
    dst = os.path.join(tmp, "mpm_solver_warp")
    shutil.copytree(src, dst)
    utils = os.path.join(dst, "warp_utils.py")
    text = open(utils).read()
    text = text.replace("import warp.torch\n", "import warp\n").replace("warp.types.float32", "wp.float32")
    open(utils, "w").write(text)
    mpm = os.path.join(dst, "mpm_utils.py")
    text = open(mpm).read()
    assert text.count(OLD_V) == 1, "the release's g2p_flip line is not where expected"
    text = text.replace(OLD_V, OLD_V_GUARDED)
    if variant in ("unweighted_force", "elastic_unweighted_force"):
        assert text.count(WEIGHTED_FORCE) == 1, "the release's FLIP P2G force line is not where expected"
        text = text.replace(WEIGHTED_FORCE, "v_out_add = dt * elastic_force")
    if variant == "no_case3_hardening":
        assert text.count(CASE3_HARDENING) == 1, "the release's case-3 hardening line is not where expected"
        text = text.replace(CASE3_HARDENING, "if False")
    elif variant not in VARIANTS:
        sys.exit("unknown variant %r: one of %s" % (variant, ", ".join(VARIANTS)))
    open(mpm, "w").write(text)
    stubs = os.path.join(tmp, "stubs")
    os.makedirs(stubs)
    for name in ("torch", "h5py"):
        open(os.path.join(stubs, name + ".py"), "w").close()
    sys.path[:0] = [dst, stubs]
    return dst


def run(snapshot, particles, n_grid, frames, out, variant="as_released"):
    patched_solver(snapshot, variant)
    import warp as wp
    wp.config.quiet = True
    # WARP_MODE=debug bounds-checks every array access (slower): an out-of-range grid index
    # is reported instead of crashing the process.
    wp.config.mode = os.environ.get("WARP_MODE", "release")
    wp.init()
    # The release builds its B-spline weights as wp.mat33(wa, wb, wc) and reads w[axis,
    # node]: the vectors are columns, as warp-lang 1.x (checked on 1.10) still reads them;
    # rewriting it as wp.matrix_from_rows would transpose the weights.
    from mpm_solver_warp import MPM_Simulator_WARP
    from warp_utils import set_mat33_to_identity
    os.makedirs(out, exist_ok=True)
    dev, grid_lim = "cpu", 2.0
    dx = grid_lim / n_grid
    p = read_particles(particles)
    x = np.stack([p["x"], p["y"], p["z"]], 1).astype(np.float32)
    vol = p["volume"].astype(np.float32)
    seeds = p["material"] == SEED_MATERIAL
    n = len(x)
    sim = MPM_Simulator_WARP(10, device=dev)
    sim.initialize(n, n_grid, grid_lim, device=dev)
    sim.mpm_state.particle_x = wp.from_numpy(x, dtype=wp.vec3, device=dev)
    sim.mpm_state.particle_vol = wp.from_numpy(vol, dtype=float, device=dev)
    # As the driver's load_initial_data_from_torch: F starts at the identity.
    wp.launch(kernel=set_mat33_to_identity, dim=n, inputs=[sim.mpm_state.particle_F_trial], device=dev)
    material = "jelly" if variant.startswith("elastic") else "watermelon"
    sim.set_parameters_dict({"material": material, "E": E, "nu": NU, "density": RHO,
                             "beta": BETA, "xi": XI, "hardening": 1, "friction_angle": PHI,
                             "g": [0.0, 0.0, GRAVITY], "n_grid": n_grid, "grid_lim": grid_lim},
                            device=dev)
    beta = sim.mpm_model.beta.numpy()
    beta[seeds] = SEED_BETA
    sim.mpm_model.beta.assign(beta)
    sim.add_bounding_box()
    sim.add_surface_collider((1.0, 1.0, 0.0), (0.0, 0.0, 1.0), "sticky", 0.0)
    sim.finalize_mu_lam(device=dev)
    v = np.zeros((n, 3), np.float32)
    v[:, 2] = V0
    sim.mpm_state.particle_v = wp.from_numpy(v, dtype=wp.vec3, device=dev)
    c = np.sqrt(E * (1 - NU) / ((1 + NU) * (1 - 2 * NU) * RHO))
    dt = CFL * dx / c
    per = int(FRAME_DT / dt)
    print("n_grid %d dx %.4f particles %d seeds %d dt %.3e steps/frame %d, %s"
          % (n_grid, dx, n, seeds.sum(), dt, per, variant), flush=True)
    write_particles(os.path.join(out, "frame_00000.ply"), x, v, np.full(n, ALPHA0), dx, 0)
    t0, step = time.perf_counter(), 0
    for f in range(1, frames + 1):
        for _ in range(per):
            sim.p2g2p(step, dt, device=dev, flip_pic_ratio=FLIP)
            step += 1
            # A non-finite position would index the grid out of bounds in the next P2G
            # (a crash in warp's release mode): stop with what went wrong instead.
            xs = sim.mpm_state.particle_x.numpy()
            bad = ~np.isfinite(xs).all(1) | (xs < 0).any(1) | (xs >= grid_lim).any(1)
            if bad.any():
                i = np.flatnonzero(bad)
                F = sim.mpm_state.particle_F.numpy()[i[0]]
                sys.exit("step %d (frame %d): %d particle(s) left the grid or became non-finite; "
                         "the first, %d (seed %s), has x %s, log Jp %s, det F %s"
                         % (step, f, len(i), i[0], seeds[i[0]], xs[i[0]],
                            sim.mpm_state.particle_Jp.numpy()[i[0]], np.linalg.det(F)))
        xs = sim.mpm_state.particle_x.numpy()
        vs = sim.mpm_state.particle_v.numpy()
        jp = sim.mpm_state.particle_Jp.numpy()
        write_particles(os.path.join(out, "frame_%05d.ply" % f), xs, vs, jp, dx, f)
        print("frame %d: lowest z %.3f, fastest %.2f m/s, damaged (log Jp >= 0) %.1f%%, finite %s, %.0f s"
              % (f, xs[:, 2].min(), np.linalg.norm(vs, axis=1).max(), 100 * (jp >= 0).mean(),
                 np.isfinite(xs).all(), time.perf_counter() - t0), flush=True)


def main():
    a = sys.argv[1:]
    if len(a) in (3, 4) and a[0] == "scene":
        scene(int(a[1]), a[2], *a[3:])
    elif len(a) in (6, 7) and a[0] == "run":
        run(a[1], a[2], int(a[3]), int(a[4]), a[5], *a[6:])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
