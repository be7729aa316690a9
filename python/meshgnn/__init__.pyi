"""Type stubs of the meshgnn package (functions documented in _native.pyi)."""

from dataclasses import dataclass
from typing import List, Sequence, Union

import numpy as np
import numpy.typing as npt
import scipy.sparse

from ._native import (
    chamfer as chamfer,
    farthest_point_sampling as farthest_point_sampling,
    knn as knn,
    mesh_metrics as mesh_metrics,
    point_cloud_metrics as point_cloud_metrics,
    point_simplify as point_simplify,
    read_mesh as read_mesh,
    read_points as read_points,
    simplify as simplify,
    weighted_sampling as weighted_sampling,
    write_mesh as write_mesh,
    write_points as write_points,
)

__version__: str

@dataclass(frozen=True)
class MeshHierarchy:
    vertices: List[npt.NDArray[np.float32]]
    faces: List[npt.NDArray[np.int64]]
    adjacency: List[scipy.sparse.csr_matrix]
    down: List[scipy.sparse.csr_matrix]
    up: List[scipy.sparse.csr_matrix]
    spirals: List[npt.NDArray[np.int64]]
    spiral_valid: List[npt.NDArray[np.int64]]
    def padded_spirals(self, level: int) -> npt.NDArray[np.int64]: ...

def mesh_hierarchy(
    V: npt.ArrayLike,
    F: npt.ArrayLike,
    factors: Sequence[float] = (4, 4, 4, 4),
    spiral_length: Union[int, Sequence[int]] = 9,
    dilation: Union[int, Sequence[int]] = 1,
) -> MeshHierarchy: ...
