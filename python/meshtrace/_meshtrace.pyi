"""Type stubs of meshtrace's extension module (python/src); the package re-exports it."""

import os
from collections.abc import Iterator, Sequence
from typing import Literal, Optional, Union

import numpy as np
import numpy.typing as npt

__version__: str
PRESETS: list[str]

_Path = Union[str, "os.PathLike[str]"]
_Vec3 = Sequence[float]

class MeshtraceError(ValueError):
    """An input or a request meshtrace cannot render: the command line's one-line message."""

class Camera:
    """Where a camera stands, where it looks and its projection."""

    @staticmethod
    def look_at(
        eye: _Vec3,
        target: _Vec3,
        up: _Vec3 = ...,
        fov: float = 40.0,
        aperture: float = 0.0,
        focus_distance: Optional[float] = None,
    ) -> Camera: ...
    @staticmethod
    def orthographic(eye: _Vec3, target: _Vec3, height: float, up: _Vec3 = ...) -> Camera: ...
    @staticmethod
    def from_matrix(
        matrix: npt.ArrayLike,
        fov: float = 40.0,
        convention: Literal["opengl", "opencv"] = "opengl",
        ortho_height: Optional[float] = None,
    ) -> Camera: ...
    def matrix(self, convention: Literal["opengl", "opencv"] = "opengl") -> npt.NDArray[np.float64]: ...
    def intrinsics(self, width: int, height: int) -> npt.NDArray[np.float64]: ...
    @property
    def position(self) -> list[float]: ...
    @property
    def forward(self) -> list[float]: ...
    @property
    def up(self) -> list[float]: ...
    @property
    def right(self) -> list[float]: ...
    @property
    def fov(self) -> float: ...
    @property
    def ortho_height(self) -> Optional[float]: ...

class Scene:
    """A loaded scene."""

    @staticmethod
    def from_dict(
        d: dict,
        *,
        base: Optional[_Path] = None,
        environment: Optional[_Path] = None,
        max_texture_size: Optional[int] = None,
    ) -> Scene: ...
    @property
    def path(self) -> Optional[str]: ...
    @property
    def camera(self) -> Camera: ...
    @property
    def triangles(self) -> int: ...
    @property
    def framed(self) -> Optional[tuple[list[float], list[float]]]: ...
    @property
    def bounds(self) -> tuple[list[float], list[float]]: ...
    @property
    def warnings(self) -> list[str]: ...

class Output:
    """A render's images by name: a read-only mapping of NumPy arrays."""

    def __getitem__(self, key: str) -> np.ndarray: ...
    def __contains__(self, key: object) -> bool: ...
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[str]: ...
    def keys(self) -> list[str]: ...
    def values(self) -> list[np.ndarray]: ...
    def items(self) -> list[tuple[str, np.ndarray]]: ...
    def get(self, key: str, default: Optional[np.ndarray] = None) -> Optional[np.ndarray]: ...
    @property
    def samples(self) -> int: ...
    @property
    def rays(self) -> int: ...
    def save(
        self,
        path: _Path,
        *,
        bit_depth: Optional[Literal[8, 16]] = None,
        view_transform: Optional[_View] = None,
    ) -> None: ...

_View = Literal["standard", "filmic", "agx"]
_Aov = Literal["depth", "normal", "albedo", "alpha", "object_id", "material_id", "bvh_cost", "diffuse_color"]

class Renderer:
    """A device opened once and kept across renders."""

    def __init__(
        self,
        device: Literal["auto", "cpu", "gpu"] = "auto",
        *,
        adapter: Optional[str] = None,
        accel: Optional[Literal["auto", "software", "hardware"]] = None,
        threads: Optional[int] = None,
    ) -> None: ...
    @property
    def device(self) -> Literal["cpu", "gpu"]: ...
    @property
    def name(self) -> str: ...
    @property
    def notice(self) -> Optional[str]: ...
    def render(
        self,
        scene: Union[Scene, _Path],
        *,
        camera: Optional[Camera] = None,
        width: Optional[int] = None,
        height: Optional[int] = None,
        spp: Optional[int] = None,
        max_depth: Optional[int] = None,
        seed: Optional[int] = None,
        caustics: Optional[bool] = None,
        branches: Optional[int] = None,
        filter_width: Optional[float] = None,
        diffuse_bounces: Optional[int] = None,
        glossy_bounces: Optional[int] = None,
        transmission_bounces: Optional[int] = None,
        aovs: Optional[Sequence[_Aov]] = None,
        transparent: Optional[bool] = None,
        geometry_only: Optional[bool] = None,
        denoise: Optional[bool] = None,
        up: Optional[Literal["x", "y", "z"]] = None,
        environment: Optional[_Path] = None,
        lighting: Optional[Union[str, dict]] = None,
        max_texture_size: Optional[int] = None,
    ) -> Output: ...

def load(
    path: _Path,
    *,
    up: Optional[Literal["x", "y", "z"]] = None,
    environment: Optional[_Path] = None,
    lighting: Optional[Union[str, dict]] = None,
    max_texture_size: Optional[int] = None,
    studio: bool = True,
) -> Scene: ...
def save(
    output: Output,
    path: _Path,
    *,
    bit_depth: Optional[Literal[8, 16]] = None,
    view_transform: Optional[_View] = None,
) -> None: ...
def orbit(
    scene: Scene, views: int = 12, elevation: Optional[float] = None, azimuth: Optional[float] = None
) -> list[Camera]: ...
def preset(
    scene: Scene, name: str, views: Optional[int] = None, uid: Optional[str] = None
) -> list[Camera]: ...
def preset_settings(name: str) -> dict[str, Union[int, float, bool]]: ...
