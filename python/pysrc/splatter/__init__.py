"""splatter: simulate and render 3D Gaussian Splatting scenes from Python.

Read a capture, simulate a scene and get its frames and Gaussians as numpy arrays::

    import splatter
    splats = splatter.read("capture.ply")            # every format splatter reads
    scene = splatter.Scene.load("scenes/jelly.json")  # validated as the CLI does
    for frame in splatter.run(scene, frames=range(0, 12), deterministic=True):
        frame.image       # (height, width, 3) uint8
        frame.splats      # the frame's Gaussians (Splats)
        frame.damage      # per particle, for fracturing materials

Everything here is the Rust library underneath (``splatter._native``): the same readers,
the same scene validation and error messages, the same run loop as ``splatter render``.
"""

from __future__ import annotations

import json
import os
import queue
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Optional, Sequence, Union

import numpy as np

from . import _native
from ._native import SceneError

__all__ = [
    "Splats",
    "Scene",
    "SceneError",
    "Frame",
    "read",
    "run",
    "render",
    "adapter",
]
__version__ = _native.__version__

PathLike = Union[str, "os.PathLike[str]"]


class Splats:
    """Gaussians as arrays: ``means`` (n, 3), ``scales`` (n, 3, linear, not log),
    ``rotations`` (n, 4, unit quaternions as w, x, y, z), ``opacities`` (n,, in (0, 1],
    not logits), ``sh`` (n, K, 3, coefficient-major: K = 1, 4, 9 or 16 for SH degree 0–3),
    and optional region ``labels`` (n,, int32 indices into ``label_names``, -1 for none).
    All float arrays are float32."""

    def __init__(
        self,
        means: np.ndarray,
        scales: np.ndarray,
        rotations: np.ndarray,
        opacities: np.ndarray,
        sh: np.ndarray,
        labels: Optional[np.ndarray] = None,
        label_names: Sequence[str] = (),
    ) -> None:
        f32 = lambda a: np.ascontiguousarray(a, dtype=np.float32)  # noqa: E731
        self.means = f32(means)
        self.scales = f32(scales)
        self.rotations = f32(rotations)
        self.opacities = f32(opacities)
        sh = f32(sh)
        if sh.ndim == 2 and sh.shape[1] == 3:
            sh = sh[:, None, :]
        self.sh = sh
        self.labels = None if labels is None else np.ascontiguousarray(labels, dtype=np.int32)
        self.label_names = list(label_names)
        n = len(self.means)
        for name, a, shape in [
            ("means", self.means, (n, 3)),
            ("scales", self.scales, (n, 3)),
            ("rotations", self.rotations, (n, 4)),
            ("opacities", self.opacities, (n,)),
        ]:
            if a.shape != shape:
                raise ValueError(f"{name}: expected shape {shape}, got {a.shape}")

    @classmethod
    def _from_dict(cls, d: dict) -> "Splats":
        return cls(
            d["means"], d["scales"], d["rotations"], d["opacities"], d["sh"],
            d["labels"], d["label_names"],
        )

    def __len__(self) -> int:
        return len(self.means)

    def __repr__(self) -> str:
        degree = int(round(np.sqrt(self.sh.shape[1]))) - 1
        labelled = f", {len(self.label_names)} labels" if self.label_names else ""
        return f"Splats({len(self)} Gaussians, SH degree {degree}{labelled})"

    @property
    def sh_degree(self) -> int:
        return int(round(np.sqrt(self.sh.shape[1]))) - 1

    def write(self, path: PathLike) -> None:
        """Write a splat file, its format from the extension: .ply (3DGS), .spz (version 3),
        .splat or .glb (KHR_gaussian_splatting). Labels travel in PLY, SPZ and GLB."""
        _native.write_splats_file(
            os.fspath(path), self.means, self.scales, self.rotations, self.opacities,
            self.sh, self.labels, self.label_names,
        )


def read(path: PathLike) -> Splats:
    """Read a splat file of any format splatter reads: 3DGS PLY, SuperSplat compressed PLY,
    SPZ, SOG (a folder or its meta.json), .splat, GLB. A PLY's integer ``label`` (or
    ``segment``) property becomes ``labels``."""
    return Splats._from_dict(_native.read_splats(os.fspath(path)))


class Scene:
    """A scene file's content, parsed and validated as ``splatter render`` validates it.
    Build one with :meth:`load` or :meth:`from_dict`; an invalid scene raises
    :class:`SceneError` naming the field, its value and what was expected."""

    def __init__(self, text: str, origin: str, base_dir: str, path: Optional[str]) -> None:
        self._text = text
        self.origin = origin
        self.base_dir = base_dir
        self.path = path
        self.name = _native.check_scene(text, origin, base_dir)

    @classmethod
    def load(cls, path: PathLike) -> "Scene":
        """Read a scene file; relative paths in it resolve against its folder."""
        path = os.fspath(path)
        text, base_dir = _native.load_scene(path)
        return cls(text, path, base_dir, path)

    @classmethod
    def from_dict(cls, d: dict, base_dir: PathLike = ".", name: str = "scene.json") -> "Scene":
        """A scene from a dict with the scene file's structure (docs/scene-format.md);
        relative paths resolve against ``base_dir``; ``name`` names it in messages."""
        return cls(json.dumps(d), name, os.fspath(base_dir), None)

    def to_dict(self) -> dict:
        """The scene as a dict (edit it and make a new one with :meth:`from_dict`)."""
        return json.loads(self._text)

    def __repr__(self) -> str:
        return f"Scene({self.name!r})"


@dataclass
class Frame:
    """One rendered frame: ``index``, ``image`` (height, width, 3) uint8 (×4 with the alpha
    pass), ``path`` (its PNG), and when asked
    for, its Gaussians ``splats`` and its particles' ``positions`` (m, 3) and ``damage``
    (m,; None for materials without damage)."""

    index: int
    image: np.ndarray
    path: Path
    splats: Optional[Splats] = None
    positions: Optional[np.ndarray] = None
    damage: Optional[np.ndarray] = None


def _frame_set(frames: Union[None, int, range, str]) -> Optional[str]:
    if frames is None:
        return None
    if isinstance(frames, int):
        return str(frames)
    if isinstance(frames, range):
        if frames.step != 1:
            return f"{frames.start}-{frames.stop - 1}:{frames.step}"
        return f"{frames.start}..{frames.stop}"
    return str(frames)


def _wait_for(path: Path, worker: threading.Thread) -> None:
    # The run queues each PNG for its writer threads and renames it into place when done.
    while not path.exists():
        if not worker.is_alive() and not path.exists():
            raise RuntimeError(f"the run stopped before writing {path}")
        time.sleep(0.005)


def run(
    scene: Optional[Union[Scene, PathLike]] = None,
    frames: Union[None, int, range, str] = None,
    deterministic: bool = False,
    out: Optional[PathLike] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    gaussians: bool = False,
    particles: bool = False,
    alpha: bool = False,
    backend: Optional[str] = None,
    progress: bool = True,
) -> Iterator[Frame]:
    """Simulate and render ``scene`` (a :class:`Scene`, a scene file's path, or None for
    the default scene) frame by frame, as ``splatter render`` does, yielding each
    :class:`Frame` as it is written. ``frames``: a ``range``, one frame, or the CLI's
    syntax (``"0..12"``, ``"1-3,5"``). ``out``: where the frames go (a temporary folder by
    default, removed when the iteration ends). ``gaussians`` / ``particles``: also read each
    frame's Gaussians / particles back. ``alpha``: each ``image`` is (height, width, 4),
    the alpha pass (straight colour and α; over the scene's background it is the frame). ``backend``: ``"vulkan"``, ``"gl"``, ``"metal"`` or
    ``"dx12"`` to force one (default: the adapter the CLI would choose). A progress bar
    shows when ``tqdm`` is installed and ``progress`` is true."""
    if scene is None or isinstance(scene, Scene):
        s = scene
    else:
        s = Scene.load(scene)
    temp = None
    if out is None:
        temp = tempfile.TemporaryDirectory(prefix="splatter-")
        out_dir = Path(temp.name)
    else:
        out_dir = Path(out)
    done: "queue.Queue[Any]" = queue.Queue()
    failure: list = []

    def work() -> None:
        try:
            _native.run_scene(
                s.path if s is not None else None,
                s._text if s is not None and s.path is None else None,
                s.origin if s is not None else "default.json",
                s.base_dir if s is not None else ".",
                os.fspath(out_dir),
                _frame_set(frames),
                deterministic,
                backend,
                width,
                height,
                alpha,
                gaussians,
                particles,
                done.put,
            )
        except BaseException as e:  # handed to the consumer
            failure.append(e)
        finally:
            done.put(None)

    worker = threading.Thread(target=work, name="splatter-run", daemon=True)
    worker.start()
    bar = _progress_bar(progress)
    try:
        while True:
            index = done.get()
            if index is None:
                break
            png = out_dir / f"frame_{index:05d}.png"
            _wait_for(png, worker)
            if alpha:
                a = out_dir / "alpha" / f"frame_{index:05d}.png"
                _wait_for(a, worker)
                image = _native.read_frame(os.fspath(a), True)
            else:
                image = _native.read_frame(os.fspath(png))
            frame = Frame(index=index, image=image, path=png)
            if gaussians:
                frame.splats = read(out_dir / "gaussians" / f"frame_{index:05d}.ply")
            if particles:
                p = _native.read_particles(os.fspath(out_dir / "particles" / f"frame_{index:05d}.ply"))
                frame.positions = p["positions"]
                frame.damage = p["damage"]
            if bar is not None:
                bar.update(1)
            yield frame
        worker.join()
        if failure:
            raise failure[0]
    finally:
        if bar is not None:
            bar.close()
        if temp is not None:
            worker.join()
            temp.cleanup()


def _progress_bar(progress: bool) -> Any:
    if not progress:
        return None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None
    return tqdm(unit="frame", desc="splatter")


def render(
    splats: Splats,
    camera: Optional[dict] = None,
    width: int = 640,
    height: int = 360,
    background: Sequence[float] = (0.0, 0.0, 0.0),
    backend: Optional[str] = None,
) -> np.ndarray:
    """Render Gaussians to an (height, width, 3) uint8 image. ``camera``: a dict with
    ``position`` and ``target`` (and optionally ``up``, default +z, and ``fov_y_deg``,
    default 50); None frames the Gaussians as ``splatter render --ply`` does (an orbit round
    their robust bounds, about their estimated up)."""
    cam = None
    if camera is not None:
        cam = (
            tuple(float(v) for v in camera["position"]),
            tuple(float(v) for v in camera["target"]),
            tuple(float(v) for v in camera.get("up", (0.0, 0.0, 1.0))),
            float(camera.get("fov_y_deg", 50.0)),
        )
    return _native.render_splats(
        splats.means, splats.scales, splats.rotations, splats.opacities, splats.sh,
        width, height, cam, tuple(float(v) for v in background), backend,
    )


def adapter(backend: Optional[str] = None) -> str:
    """The adapter a run takes (or the one ``backend`` forces), described."""
    return _native.adapter(backend)
