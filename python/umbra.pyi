"""The umbra engine from Python: the classic hidden-surface and shadow algorithms."""

from os import PathLike
from typing import Dict, List, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

class UmbraError(Exception):
    """What the engine refused: a scene file's problem (file and line), an unknown stage or
    option, a frame over the memory budget."""

class Scene:
    """A loaded, checked scene."""

    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def polygons(self) -> int: ...
    @property
    def lights(self) -> int: ...
    def with_size(self, width: int, height: int) -> "Scene":
        """The same scene at another image size."""

class Frame:
    """A rendered frame."""

    image: npt.NDArray[np.uint8]
    """(height, width, 3) image."""
    face_ids: npt.NDArray[np.uint32]
    """(height, width) face id per pixel; 4294967295 on background."""
    light: List[npt.NDArray[np.float32]]
    """Per light, (height, width) lit fraction."""
    counters: Dict[str, int]
    """The stages' counters, "visibility.<name>" and "shadow.<name>"."""
    times: Dict[str, float]
    """Milliseconds per phase, and "total"."""

def load(path: Union[str, PathLike[str]]) -> Scene:
    """Loads a scene file; raises UmbraError naming the file and line of a problem."""

def render(
    scene: Scene,
    visibility: str = "scanline",
    shadows: str = "bouknight-kelley",
    paper: bool = False,
    gamma: Optional[float] = 2.2,
    **settings: object,
) -> Frame:
    """Renders the scene with a visibility and a shadow stage (paper=True: as published).
    Keyword settings set the stage's options by their names in the engine: prefilter,
    sphere_grid, seen_receivers, drop_behind, wedge, slab, solid_outlines, own_solid, solid_cull,
    convex_split, backgrounds, lone_sheets, whole_solids, tiling, face_binning, sort_grid, counting
    ("zpass", "zfail", "naive-zpass"),
    construction ("merged", "per-polygon", "crow-1977"), sight_cuts, far_outline, front_outline, map_size,
    bias, slope_bias, normal_offset, receiver_plane, cull_front, fit_to_view, hull_cull,
    convex_bodies, same_solid, premise_fallback, lambert."""

def bench(
    scene: Scene,
    shadows: Sequence[str] = ("bouknight-kelley",),
    visibility: Sequence[str] = ("scanline",),
    runs: int = 5,
    warmup: int = 1,
    paper: bool = False,
    **settings: object,
) -> List[Dict[str, object]]:
    """Times every pair of stages: one dict per pair (median_ms, min_ms, max_ms, times_ms,
    phases, counters)."""
