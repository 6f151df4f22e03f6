"""Type stubs of the vcm module (the native part is vcm._vcm)."""

import os
from typing import Any, Dict, List, Optional, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str
ALGORITHMS: List[str]
"""Algorithm names: pt, el, lt, ppm, bpm, bpt, vcm."""

Image = npt.NDArray[np.float32]
"""float32 array (height, width, 3), linear sRGB, top row first."""
ImageLike = Union[npt.ArrayLike, str, "os.PathLike[str]"]
PathLike = Union[str, "os.PathLike[str]"]

class BuiltinScene(TypedDict):
    id: int
    name: str
    mask: int
    description: str

class ZTest(TypedDict):
    passed: bool
    failing: int
    entries: int
    worst_z: float
    worst_pixel: Tuple[int, int]
    worst_channel: int
    threshold_p: float

class Comparison(TypedDict):
    pixels: int
    non_finite: int
    rmse: float
    relmse: float
    mae: float
    means_a: List[float]
    means_b: List[float]
    z_test: Optional[ZTest]

class Scene:
    """A built-in Cornell box or a scene file with its parameters (see load_file)."""

    @property
    def name(self) -> str: ...
    @property
    def resolution(self) -> Tuple[int, int]:
        """(width, height) of the scene's own film."""
    @property
    def warnings(self) -> List[str]: ...

def load_file(path_or_builtin: PathLike, **params: Any) -> Scene:
    """Loads a built-in scene (name or id) or a Mitsuba 3 / pbrt-v4 file; keyword arguments set
    the file's $name parameters. FileNotFoundError for a missing file, ValueError (with
    file:line:column) for an invalid one."""

def scenes() -> List[BuiltinScene]:
    """The built-in scenes."""

def render(
    scene: Scene,
    *,
    algorithm: str = "vcm",
    iterations: Optional[int] = None,
    time: Optional[float] = None,
    resolution: Optional[Tuple[int, int]] = None,
    seed: int = 0,
    threads: Optional[int] = None,
    max_length: Optional[int] = None,
    spectral: bool = False,
    radius_factor: Optional[float] = None,
    radius_alpha: Optional[float] = None,
    volume_radius_factor: Optional[float] = None,
    radius_mode: str = "global",
    memory_efficient: bool = False,
    rr_depth: Union[int, str, None] = None,
    heuristic: str = "balance",
    light_sampler: str = "tree",
    mis_compensation: bool = True,
    sampler: str = "sobol",
    parallelism: str = "auto",
    max_memory: Optional[int] = None,
    permissive: bool = False,
) -> Image:
    """Renders the scene; the same image as `vcm render` with the same settings. `iterations`
    (default: the file's sample count, else 64) or `time` in seconds; threads=None: all cores.
    Ctrl-C stops after the current iteration and raises KeyboardInterrupt."""

class Session:
    """A progressive render stepped from Python; stepping to N iterations gives the image of
    render(..., iterations=N)."""

    def __init__(
        self,
        scene: Scene,
        *,
        algorithm: str = "vcm",
        resolution: Optional[Tuple[int, int]] = None,
        seed: int = 0,
        threads: Optional[int] = None,
        max_length: Optional[int] = None,
        spectral: bool = False,
        radius_factor: Optional[float] = None,
        radius_alpha: Optional[float] = None,
        volume_radius_factor: Optional[float] = None,
        radius_mode: str = "global",
        memory_efficient: bool = False,
        rr_depth: Union[int, str, None] = None,
        heuristic: str = "balance",
        light_sampler: str = "tree",
        mis_compensation: bool = True,
        sampler: str = "sobol",
        parallelism: str = "auto",
        max_memory: Optional[int] = None,
        permissive: bool = False,
        techniques: bool = False,
        technique_length: int = 4,
    ) -> None: ...
    @staticmethod
    def resume(path: PathLike, threads: Optional[int] = None) -> "Session":
        """Continues a checkpoint (Session.checkpoint or `vcm render --checkpoint`)."""
    def step(self, n: int = 1) -> int:
        """Renders n more iterations; returns the iteration count. Ctrl-C: KeyboardInterrupt
        after the current iteration, the session stays usable."""
    @property
    def iterations(self) -> int: ...
    @property
    def seconds(self) -> float:
        """Wall-clock seconds spent in step()."""
    @property
    def resolution(self) -> Tuple[int, int]:
        """(width, height)."""
    def image(self) -> Image: ...
    def variance(self) -> Image:
        """Per-pixel variance of the image (of the mean)."""
    def techniques(self) -> Dict[str, Image]:
        """Family images (emitter-hit, next-event, light-tracing, connection, merging) and (s, t)
        images; each set sums to the image. Needs techniques=True."""
    def checkpoint(self, path: PathLike) -> None: ...

def read(path: PathLike) -> Image:
    """Reads an EXR, PFM, HDR or PNG file (linear sRGB)."""

def write(path: PathLike, array: npt.ArrayLike, exposure: float = 0.0) -> None:
    """Writes an (height, width, 3) array as EXR, PFM, HDR or PNG (by extension)."""

def compare(
    a: ImageLike,
    b: ImageLike,
    variance_a: Optional[ImageLike] = None,
    variance_b: Optional[ImageLike] = None,
    alpha: float = 1e-3,
) -> Comparison:
    """Metrics of test image a against reference b, as `vcm compare`; with both variances the
    per-pixel Z-test (Sidak-corrected at family-wise level alpha)."""
