"""meshgnn from Python: QEM simplification, the COMA / Neural3DMM / SpiralNet++ mesh
hierarchy, farthest point sampling, k-NN, Chamfer and the thesis' evaluation metrics, computed
in Rust on numpy arrays.

Arrays in: positions float32 or float64 ``(n, 3)`` (borrowed without a copy when C-contiguous
float32), faces int32 or int64 ``(m, 3)``. Arrays out: positions float32, indices int64.
Every function releases the GIL while it computes, so threads (and Dask, Ray or Spark
workers) run in parallel. Bad input raises ``ValueError`` (a file that cannot be read or
written, ``OSError``) with the one-line message of the command-line tools.

See docs/python.md for a COMA-style preprocessing example.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Sequence, Union

import numpy as np
import scipy.sparse

from . import _native
from ._native import (
    chamfer,
    farthest_point_sampling,
    knn,
    mesh_metrics,
    point_cloud_metrics,
    point_simplify,
    read_mesh,
    read_points,
    simplify,
    weighted_sampling,
    write_mesh,
    write_points,
)

__version__ = _native.__version__

__all__ = [
    "MeshHierarchy",
    "chamfer",
    "farthest_point_sampling",
    "knn",
    "mesh_hierarchy",
    "mesh_metrics",
    "point_cloud_metrics",
    "point_simplify",
    "read_mesh",
    "read_points",
    "simplify",
    "weighted_sampling",
    "write_mesh",
    "write_points",
]


@dataclass(frozen=True)
class MeshHierarchy:
    """The multi-resolution template of a spiral mesh autoencoder, finest level first.

    ``vertices[i]`` float32 ``(n_i, 3)`` and ``faces[i]`` int64 ``(m_i, 3)``: level ``i``
    (level 0 is the template; each vertex of level ``i + 1`` is a vertex of level ``i``).
    ``adjacency[i]``: the ``n_i × n_i`` vertex adjacency (COMA's ``A``).
    ``down[i]``: ``n_{i+1} × n_i`` selection matrix, ``down[i] @ vertices[i] == vertices[i+1]``
    (COMA's ``D``). ``up[i]``: ``n_i × n_{i+1}`` barycentric interpolation, rows summing to 1
    (COMA's ``U``). ``spirals[i]``: int64 ``(n_i, L_i)``, row ``v`` starts at ``v``; a spiral
    shorter than ``L_i`` (a small component) repeats its last entry, with the number of real
    entries in ``spiral_valid[i]``. Use :meth:`padded_spirals` for Neural3DMM's convention.
    """

    vertices: List[np.ndarray]
    faces: List[np.ndarray]
    adjacency: List[scipy.sparse.csr_matrix]
    down: List[scipy.sparse.csr_matrix]
    up: List[scipy.sparse.csr_matrix]
    spirals: List[np.ndarray]
    spiral_valid: List[np.ndarray]

    def padded_spirals(self, level: int) -> np.ndarray:
        """``spirals[level]`` with every padded entry replaced by ``n_level``, the index of
        the zero dummy vertex Neural3DMM appends to each level."""
        spirals = self.spirals[level].copy()
        columns = np.arange(spirals.shape[1])[None, :]
        spirals[columns >= self.spiral_valid[level][:, None]] = spirals.shape[0]
        return spirals


def mesh_hierarchy(
    V,
    F,
    factors: Sequence[float] = (4, 4, 4, 4),
    spiral_length: Union[int, Sequence[int]] = 9,
    dilation: Union[int, Sequence[int]] = 1,
) -> MeshHierarchy:
    """Builds the mesh hierarchy of the template ``(V, F)``: ``len(factors)`` QEM decimations
    (each dividing the face count by its factor, vertices kept at original positions), the
    down/up-sampling matrices between consecutive levels and the spirals of every level.

    ``spiral_length`` and ``dilation``: one value for every level, or one per level
    (``len(factors) + 1`` values). Raises ``ValueError`` naming the problem when the template
    is not a single edge-manifold, consistently oriented component or is too small.
    """
    levels = len(factors) + 1
    lengths = _per_level(spiral_length, "spiral_length", levels)
    dilations = _per_level(dilation, "dilation", levels)
    parts = _native.mesh_hierarchy(V, F, [float(f) for f in factors], lengths, dilations)
    sparse = {
        key: [scipy.sparse.csr_matrix((d, i, p), shape=s) for d, i, p, s in parts[key]]
        for key in ("adjacency", "down", "up")
    }
    return MeshHierarchy(
        vertices=parts["vertices"],
        faces=parts["faces"],
        spirals=parts["spirals"],
        spiral_valid=parts["spiral_valid"],
        **sparse,
    )


def _per_level(value, name: str, levels: int) -> List[int]:
    values = [value] if isinstance(value, (int, np.integer)) else list(value)
    if len(values) not in (1, levels):
        raise ValueError(
            f"{name}: give one value for every level or {levels} (one per level), "
            f"got {len(values)}"
        )
    if any(int(v) != v or v < 1 for v in values):
        raise ValueError(f"{name}: every value must be an integer >= 1, got {values}")
    return [int(v) for v in values]
