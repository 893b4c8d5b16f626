"""The Python package against independent readers and the CLI (run by .ci/run after the
cargo tests; `pip install ./python[test]` first)."""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import splatter

ROOT = Path(__file__).resolve().parents[2]
CAPTURE = ROOT / "tests" / "data" / "captures" / "plant_14k_segmented.ply"


def cli() -> Path:
    """The CLI built by `cargo build --release` (or SPLATTER_BIN)."""
    path = Path(os.environ.get("SPLATTER_BIN", ROOT / "target" / "release" / "splatter"))
    if not path.exists():
        pytest.skip(f"no CLI at {path}: run cargo build --release first")
    return path


def test_read_equals_plyfile_on_a_real_capture():
    """Arrays read by splatter.read against plyfile's reading of the same 3DGS PLY (a
    phone capture with segment labels): means exact, scales exp(log-scale), opacities
    sigmoid(logit), rotations the normalised (w, x, y, z) quaternion, SH coefficient-major
    from f_dc and the channel-major f_rest, labels from the `segment` property."""
    plyfile = pytest.importorskip("plyfile")
    v = plyfile.PlyData.read(str(CAPTURE))["vertex"].data
    s = splatter.read(CAPTURE)
    n = len(v)
    assert len(s) == n
    means = np.stack([v["x"], v["y"], v["z"]], axis=1)
    np.testing.assert_array_equal(s.means, means.astype(np.float32))
    scales = np.exp(np.stack([v[f"scale_{i}"] for i in range(3)], axis=1))
    np.testing.assert_allclose(s.scales, scales, rtol=1e-6)
    opacities = 1.0 / (1.0 + np.exp(-v["opacity"].astype(np.float64)))
    np.testing.assert_allclose(s.opacities, opacities, rtol=1e-6, atol=1e-7)
    q = np.stack([v[f"rot_{i}"] for i in range(4)], axis=1).astype(np.float64)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    # q and −q are the same rotation
    sign = np.sign(np.sum(q * s.rotations, axis=1, keepdims=True))
    np.testing.assert_allclose(s.rotations, q * sign, atol=1e-6)
    rest = [name for name in v.dtype.names if name.startswith("f_rest_")]
    k = len(rest) // 3 + 1
    sh = np.zeros((n, k, 3))
    for c in range(3):
        sh[:, 0, c] = v[f"f_dc_{c}"]
        for j in range(k - 1):
            sh[:, j + 1, c] = v[f"f_rest_{c * (k - 1) + j}"]
    np.testing.assert_array_equal(s.sh, sh.astype(np.float32))
    assert s.labels is not None
    names = np.array(s.label_names)
    np.testing.assert_array_equal(names[s.labels].astype(int), v["segment"].astype(int))


def test_splats_write_and_read_back(tmp_path):
    """Splats built from arrays, written as PLY and read back, are the same arrays; SPZ
    keeps them within its quantisation."""
    rng = np.random.default_rng(3)
    n = 500
    rot = rng.normal(size=(n, 4))
    rot /= np.linalg.norm(rot, axis=1, keepdims=True)
    rot *= np.sign(rot[:, :1])
    s = splatter.Splats(
        means=rng.uniform(-1, 1, (n, 3)),
        scales=rng.uniform(0.01, 0.1, (n, 3)),
        rotations=rot,
        opacities=rng.uniform(0.1, 0.99, n),
        sh=rng.normal(0, 0.3, (n, 4, 3)),
    )
    s.write(tmp_path / "a.ply")
    back = splatter.read(tmp_path / "a.ply")
    for name in ["means", "scales", "opacities", "sh"]:
        np.testing.assert_allclose(getattr(back, name), getattr(s, name), rtol=1e-5, atol=1e-6, err_msg=name)
    sign = np.sign(np.sum(back.rotations * s.rotations, axis=1, keepdims=True))
    np.testing.assert_allclose(back.rotations * sign, s.rotations, atol=1e-6)
    s.write(tmp_path / "a.spz")
    spz = splatter.read(tmp_path / "a.spz")
    np.testing.assert_allclose(spz.means, s.means, atol=1e-3)
    with pytest.raises(ValueError, match=r"scales: expected shape \(10, 3\)"):
        splatter.Splats(s.means[:10], s.scales, s.rotations, s.opacities, s.sh)


def test_a_bad_scene_raises_scene_error_naming_the_field(tmp_path):
    """The CLI's validation and messages: a negative radius and an unknown field, from a
    dict and from a file."""
    scene = {
        "output": {"width": 64, "height": 48, "frames": 1},
        "camera": {"fov_y_deg": 50, "path": {"type": "orbit", "target": [0, 0, 0], "radius": 3}},
        "objects": [{"procedural": {"shape": "sphere", "radius": -1, "spacing": 0.1, "color": [1, 1, 1]}}],
    }
    with pytest.raises(splatter.SceneError, match=r"objects\[0\]\.procedural") as e:
        splatter.Scene.from_dict(scene)
    assert "-1" in str(e.value)
    scene["objects"][0]["procedural"]["radius"] = 0.5
    ok = splatter.Scene.from_dict(scene)
    assert ok.to_dict() == scene
    scene["output"]["fps_typo"] = 24
    (tmp_path / "bad.json").write_text(__import__("json").dumps(scene))
    with pytest.raises(splatter.SceneError, match="fps_typo"):
        splatter.Scene.load(tmp_path / "bad.json")


def test_a_frame_of_run_is_the_clis_frame(tmp_path):
    """splatter.run on the shipped jelly (simulated, --deterministic) against `splatter
    render` of the same scene file: the same PNG bytes, frame by frame."""
    scene = ROOT / "scenes" / "jelly.json"
    args = ["--deterministic", "--frames", "0..3", "--width", "96", "--height", "72"]
    subprocess.run(
        [str(cli()), "render", str(scene), "--out", str(tmp_path / "cli"), *args],
        check=True, capture_output=True,
    )
    frames = list(
        splatter.run(
            splatter.Scene.load(scene), frames=range(0, 3), deterministic=True,
            width=96, height=72, out=tmp_path / "py", gaussians=True, particles=True,
            progress=False,
        )
    )
    assert [f.index for f in frames] == [0, 1, 2]
    for f in frames:
        ours = (tmp_path / "py" / f"frame_{f.index:05d}.png").read_bytes()
        theirs = (tmp_path / "cli" / f"frame_{f.index:05d}.png").read_bytes()
        assert ours == theirs, f"frame {f.index} differs from the CLI's"
        assert f.image.shape == (72, 96, 3) and f.image.dtype == np.uint8
        assert f.splats is not None and len(f.splats) > 0
        assert f.positions is not None and f.positions.shape[1] == 3
    # the jelly falls: its particles move between the first and the last frame
    assert np.abs(frames[-1].positions - frames[0].positions).max() > 1e-3
    # with the alpha pass the images are RGBA, and over the background they are the frames
    bg = np.array(splatter.Scene.load(scene).to_dict()["output"].get("background", [0, 0, 0]))
    for f in splatter.run(scene, frames="0..2", deterministic=True, width=96, height=72,
                          alpha=True, progress=False):
        assert f.image.shape == (72, 96, 4)
        assert (f.image[..., 3] == 0).any() and (f.image[..., 3] == 255).any()
        a = f.image[..., 3:] / 255.0
        over = f.image[..., :3] / 255.0 * a + bg * (1 - a)
        frame = frames[f.index].image / 255.0
        assert np.abs(over - frame).max() <= 1.0 / 255 + 1e-6


def test_render_frames_a_capture_and_takes_a_camera():
    """A single image of the capture, framed as the quick look frames it, covers a good
    part of the image; a camera pointing away from it sees only the background."""
    s = splatter.read(CAPTURE)
    image = splatter.render(s, width=160, height=120)
    assert image.shape == (120, 160, 3) and image.dtype == np.uint8
    covered = (image.max(axis=2) > 10).mean()
    assert 0.1 < covered < 0.95, covered
    centre = s.means.mean(axis=0)
    away = splatter.render(
        s, camera={"position": (centre + [0, 0, 50]).tolist(), "target": (centre + [0, 0, 100]).tolist(), "up": [0, 1, 0]},
        width=64, height=48,
    )
    assert away.max() == 0
