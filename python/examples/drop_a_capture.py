# %% [markdown]
# # Drop a captured plant and watch it break
#
# A notebook in percent format (VS Code, Jupyter with jupytext, or `python
# drop_a_capture.py`): a real capture in, a simulated frame out, and the damage of its
# particles plotted over time. Run it from the repository's root after
# `pip install ./python matplotlib`; the images go to `out/python_example/`.

# %%
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import splatter

capture = Path("tests/data/captures/plant_14k.spz")
out = Path("out/python_example")
out.mkdir(parents=True, exist_ok=True)
splats = splatter.read(capture)
print(splats, "on", splatter.adapter())

# %% [markdown]
# One still of the capture as it is, framed as `splatter render --ply` frames it.

# %%
still = splatter.render(splats, width=320, height=240)
plt.imsave(out / "plant_still.png", still)

# %% [markdown]
# The same capture as a scene: stood upright, its pot filled with particles, the whole of
# a brittle material (docs/method.md §4.13), thrown down at 4 m/s onto the floor. Every
# field is the scene file's (docs/scene-format.md); a mistake raises `splatter.SceneError`
# naming it.

# %%
STRENGTH = 20000  # mean tensile strength, Pa: lower breaks more
scene = splatter.Scene.from_dict(
    {
        "output": {"width": 320, "height": 180, "frames": 12, "fps": 24},
        "camera": {
            "fov_y_deg": 40,
            "path": {"type": "orbit", "target": [0, 0, 0.8], "radius": 1.9, "height": 1.05, "start_deg": -70},
        },
        "simulation": {
            "dx": 0.03,
            "domain": {"lo": [-0.5, -0.5, 0.4], "hi": [0.5, 0.5, 1.6]},
            "ground": {"kind": "separate", "friction": 0.5},
        },
        "objects": [
            {
                "name": "plant",
                "ply": str(capture.resolve()),
                # stood upright as `splatter inspect` suggests, its pot 1 cm above the floor
                "transform": {"up": "auto", "translate": [-0.0026, -0.0074, 0.92]},
                "physics": {
                    "material": {
                        "model": "brittle", "E": 200000, "nu": 0.3, "density": 400,
                        "strength": STRENGTH, "weibull_modulus": 6, "seed": 1,
                    },
                    "select": {"box": {"lo": [-0.35, -0.35, 0.41], "hi": [0.35, 0.35, 1.5]}},
                    "particles": {"spacing": 0.02},
                    "fill": {"mode": "closing"},
                    "velocity": [0, 0, -4],
                },
            }
        ],
    },
    name="plant_drop.json",
)

# %% [markdown]
# Simulate and render it; each frame comes back with its image and its particles' damage.

# %%
mean_damage, broken = [], []
for frame in splatter.run(scene, deterministic=True, particles=True):
    d = frame.damage if frame.damage is not None else np.zeros(len(frame.positions))
    mean_damage.append(float(d.mean()))
    broken.append(float((d >= 1.0).mean()))
    last = frame
plt.imsave(out / "plant_last_frame.png", last.image)

# %%
t = np.arange(len(mean_damage)) / 24.0
fig, ax = plt.subplots(figsize=(5, 3))
ax.plot(t, mean_damage, label="mean damage")
ax.plot(t, broken, label="share broken through")
ax.set_xlabel("time (s)")
ax.set_ylabel("particles")
ax.legend()
fig.tight_layout()
fig.savefig(out / "plant_damage.png", dpi=120)
print("damage at the last frame:", mean_damage[-1])
