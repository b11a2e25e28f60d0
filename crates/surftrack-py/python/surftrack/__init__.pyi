"""Type stubs of the surftrack package (the compiled module surftrack._surftrack)."""

from os import PathLike
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike]
_Array = npt.ArrayLike

BACKENDS: List[str]

class TrackError(RuntimeError):
    """A step (or repair) failed within its bounds; the tracker keeps its previous mesh."""

class ValidationReport:
    """What Mesh.validate found."""

    @property
    def valid(self) -> bool: ...
    @property
    def vertices(self) -> int: ...
    @property
    def triangles(self) -> int: ...
    @property
    def edges(self) -> int: ...
    @property
    def non_manifold_edges(self) -> int: ...
    @property
    def counts(self) -> Dict[str, int]:
        """{category: count} for every checked category."""
    @property
    def offenders(self) -> Dict[str, List[Any]]:
        """{category: [offender, ...]} for failing categories, naming the ids."""
    def as_dict(self) -> Dict[str, Any]: ...
    def __bool__(self) -> bool: ...

class Mesh:
    """A labelled triangle mesh: float64 vertices (n, 3), int triangles (m, 3), int
    labels (m, 2) = [front, back] per triangle (label 0 is the outside)."""

    def __init__(self, vertices: _Array, triangles: _Array, labels: _Array) -> None: ...
    @staticmethod
    def read(path: _Path, stitch: bool = False) -> "Mesh":
        """Reads PLY or OBJ; stitch=True merges vertices repeated at one position on open
        edges (STL-style per-face vertices) first, then splits open edges at the open
        vertices lying on them (T-junctions); raises OSError."""
    def write(self, path: _Path) -> None:
        """Writes PLY or OBJ by extension; raises OSError."""
    @property
    def vertices(self) -> npt.NDArray[np.float64]: ...
    @property
    def triangles(self) -> npt.NDArray[np.int64]: ...
    @property
    def labels(self) -> npt.NDArray[np.int64]: ...
    @property
    def num_vertices(self) -> int: ...
    @property
    def num_triangles(self) -> int: ...
    def compacted(self) -> "Mesh": ...
    def validate(self, intersections: bool = True) -> ValidationReport: ...
    def volumes(self) -> Dict[int, float]: ...

class StepReport:
    """What one step did."""

    @property
    def stages(self) -> List[Tuple[str, float]]: ...
    @property
    def seconds(self) -> float: ...
    @property
    def events(self) -> Dict[str, int]:
        """merges, splits, t1, t2, remeshing_edits"""
    @property
    def merges(self) -> int: ...
    @property
    def splits(self) -> int: ...
    @property
    def vertices(self) -> int: ...
    @property
    def triangles(self) -> int: ...
    @property
    def substeps(self) -> int: ...

class Tracker:
    """A surface tracker ("grid" or "collision") around a valid mesh; options by name as
    the CLI's --set paths relative to the backend (see option_names(backend))."""

    def __init__(self, mesh: Mesh, backend: str = "grid", **options: Any) -> None: ...
    @property
    def backend(self) -> str: ...
    @property
    def mesh(self) -> Mesh: ...
    @property
    def vertices(self) -> npt.NDArray[np.float64]:
        """Current positions, one row per vertex slot: the shape advance() expects."""
    def advance(self, proposed: _Array) -> StepReport:
        """One step; ValueError for bad arrays, TrackError if the step fails."""
    def set_attribute(self, name: str, values: _Array) -> None:
        """Per-vertex values (n,) or (n, k), carried through every later step."""
    def attribute(self, name: str) -> npt.NDArray[np.float64]: ...
    def attribute_names(self) -> List[str]: ...
    def remove_attribute(self, name: str) -> bool: ...

class FixReport:
    """What fix did."""

    @property
    def valid(self) -> bool: ...
    @property
    def cell_size(self) -> float: ...
    @property
    def triangles_in(self) -> int: ...
    @property
    def triangles_out(self) -> int: ...
    @property
    def untouched_fraction(self) -> float: ...
    @property
    def flawed_cells(self) -> int: ...
    @property
    def stages(self) -> List[Tuple[str, float]]: ...
    @property
    def validation(self) -> ValidationReport: ...
    def as_dict(self) -> Dict[str, Any]: ...

def fix(
    mesh: Mesh,
    cell: Optional[float] = None,
    intersections: bool = True,
    allow_loss: bool = False,
    **options: Any,
) -> Tuple[Mesh, FixReport]:
    """One-shot repair / multi-material union (grid pipeline). A repair that would lose a
    material (or change the union's volume beyond the tolerance) raises TrackError unless
    allow_loss is true."""

def generate(
    scene: str,
    seed: int = 0,
    count: Optional[int] = None,
    resolution: Optional[int] = None,
    radius: Optional[float] = None,
    mesh: Optional[Mesh] = None,
) -> Mesh:
    """A built-in scene's mesh ("double-bubble", "spheres", "foam", "copies", ...)."""

def option_names(backend: Optional[str] = None) -> List[str]:
    """Every option as "path = default"."""
