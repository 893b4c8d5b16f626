"""Type stubs of the extension module (python/src/lib.rs); use the package `splatter`."""

from typing import Callable, Optional, Sequence, Tuple

import numpy as np

__version__: str

class SceneError(ValueError):
    """A scene that does not parse or validate; the message names the field, its value and
    what was expected."""

def read_splats(path: str) -> dict: ...
def write_splats_file(
    path: str,
    means: np.ndarray,
    scales: np.ndarray,
    rotations: np.ndarray,
    opacities: np.ndarray,
    sh: np.ndarray,
    labels: Optional[np.ndarray] = None,
    label_names: Sequence[str] = (),
) -> None: ...
def load_scene(path: str) -> Tuple[str, str]: ...
def check_scene(text: str, origin: str, base_dir: str) -> str: ...
def run_scene(
    path: Optional[str],
    text: Optional[str],
    origin: str,
    base_dir: str,
    out: str,
    frames: Optional[str],
    deterministic: bool,
    backend_name: Optional[str],
    width: Optional[int],
    height: Optional[int],
    alpha: bool,
    export_ply: bool,
    export_particles: bool,
    on_frame: Callable[[int], object],
) -> int: ...
def read_particles(path: str) -> dict: ...
def render_splats(
    means: np.ndarray,
    scales: np.ndarray,
    rotations: np.ndarray,
    opacities: np.ndarray,
    sh: np.ndarray,
    width: int,
    height: int,
    camera: Optional[Tuple[Sequence[float], Sequence[float], Sequence[float], float]] = None,
    background: Tuple[float, float, float] = (0.0, 0.0, 0.0),
    backend_name: Optional[str] = None,
) -> np.ndarray: ...
def read_frame(path: str, rgba: bool = False) -> np.ndarray: ...
def adapter(backend_name: Optional[str] = None) -> str: ...
