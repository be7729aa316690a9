"""Type stubs of the extension module; meshgnn/__init__.py re-exports these functions."""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike]
_Floats = npt.NDArray[Union[np.float32, np.float64]]
_Indices = npt.NDArray[Union[np.int32, np.int64]]

__version__: str

def read_mesh(path: _Path) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.int64]]:
    """Vertices (n, 3) float32 and triangles (m, 3) int64 of a mesh file (OBJ, PLY, OFF,
    glTF/GLB; polygons fan-triangulated). OSError when unreadable, ValueError when malformed."""

def write_mesh(path: _Path, V: _Floats, F: _Indices, /) -> None:
    """Writes the mesh atomically; the format follows the extension."""

def read_points(path: _Path) -> npt.NDArray[np.float32]:
    """The vertices (n, 3) float32 of any mesh or point-cloud file (also XYZ)."""

def write_points(path: _Path, X: _Floats, /) -> None:
    """Writes the points atomically (PLY, OBJ, OFF or XYZ)."""

def simplify(
    V: _Floats,
    F: _Indices,
    /,
    *,
    ratio: Optional[float] = None,
    faces: Optional[int] = None,
    method: str = "qem",
    max_error: Optional[float] = None,
    keep: Optional[Union[_Indices, Sequence[int]]] = None,
    seed: int = 0,
    weights: Optional[_Path] = None,
    fill_holes: Optional[int] = None,
    keep_positions: bool = False,
    return_vertex_map: bool = False,
    return_info: bool = False,
) -> Tuple[Any, ...]:
    """QEM edge collapse (method "qem"; `keep`: input vertices never removed nor moved, e.g.
    landmarks) or the neural mesh simplifier of thesis ch. 6 (method "neural", bundled weights
    or `weights`, seeded, holes of at most `fill_holes` edges closed, `keep_positions` leaving
    the selected vertices unplaced) to `ratio` of the faces or to `faces` faces (exactly one).
    Returns (V', F'), then
    vertex_map (vertex_map[i]: the output vertex input vertex i was merged into, or kept as;
    -1 for a vertex the neural method dropped) with return_vertex_map, then a dict
    (input_faces, output_faces, error, stop_reason, and collapses for QEM or wa_raw, wa, holes
    for neural) with return_info."""

def mesh_hierarchy(
    V: _Floats,
    F: _Indices,
    factors: List[float],
    spiral_lengths: List[int],
    dilations: List[int],
    /,
) -> Dict[str, list]:
    """Per-level arrays and CSR parts; use meshgnn.mesh_hierarchy instead."""

def farthest_point_sampling(X: _Floats, k: int, /, start: int = 0) -> npt.NDArray[np.int64]:
    """k row indices of X (n, d), any d, by farthest point sampling from row `start`."""

def weighted_sampling(w: _Floats, k: int, /, seed: int = 0) -> npt.NDArray[np.int64]:
    """k distinct indices drawn with probability proportional to the weights w (n,)."""

def knn(
    X: _Floats, k: int, /, queries: Optional[_Floats] = None
) -> Tuple[npt.NDArray[np.int64], npt.NDArray[np.float32]]:
    """(indices, squared_distances), both (q, k), nearest first, ties by index; without
    queries, each point's k nearest other points."""

def chamfer(A: _Floats, B: _Floats, /) -> Dict[str, float]:
    """forward_sum, reverse_sum, forward_mean, reverse_mean and mean (= forward_mean +
    reverse_mean) of the squared nearest-neighbour distances between A and B."""

def point_cloud_metrics(original: _Floats, simplified: _Floats, /, k: int = 16) -> Dict[str, float]:
    """cd, nc, ce, re, sdm, sdm_nearest (thesis ch. 5.4), the keys of `pcsimplify eval --json`."""

def mesh_metrics(
    V: _Floats,
    F: _Indices,
    V_simplified: _Floats,
    F_simplified: _Indices,
    /,
    samples: int = 50000,
    seed: int = 0,
) -> Dict[str, Union[float, int, bool]]:
    """cd, hausdorff, ne, wa, le, holes, edge_manifold (thesis ch. 6.4), the keys of
    `meshsimplify eval --json`."""

def point_simplify(
    X: _Floats,
    /,
    *,
    ratio: Optional[float] = None,
    points: Optional[int] = None,
    method: str = "neural",
    seed: int = 0,
    faces_of: Optional[_Indices] = None,
    weights: Optional[_Path] = None,
) -> Tuple[npt.NDArray[np.int64], npt.NDArray[np.float32]]:
    """(indices, kept points) of `pcsimplify simplify`: method neural (bundled weights), fps,
    random, tcp or qem (needs faces_of)."""
