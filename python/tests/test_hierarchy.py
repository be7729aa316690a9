"""The COMA / Neural3DMM mesh hierarchy: shapes, pooling identities, any number of levels."""

import numpy as np
import pytest
import scipy.sparse

import meshgnn


def test_pooling_matrices_satisfy_the_coma_identities(icosphere_path):
    V, F = meshgnn.read_mesh(icosphere_path)
    h = meshgnn.mesh_hierarchy(V, F, factors=(4, 2))
    assert [len(f) for f in h.faces] == [320, 80, 40]
    for i, (D, U) in enumerate(zip(h.down, h.up)):
        n_fine, n_coarse = len(h.vertices[i]), len(h.vertices[i + 1])
        assert isinstance(D, scipy.sparse.csr_matrix) and D.shape == (n_coarse, n_fine)
        assert isinstance(U, scipy.sparse.csr_matrix) and U.shape == (n_fine, n_coarse)
        np.testing.assert_array_equal(D @ h.vertices[i], h.vertices[i + 1])
        np.testing.assert_array_equal(D.sum(axis=1).A1, 1.0)
        np.testing.assert_allclose(U.sum(axis=1).A1, 1.0, rtol=1e-6)
        # U reproduces the kept vertices exactly.
        np.testing.assert_allclose(D @ (U @ h.vertices[i + 1]), h.vertices[i + 1], atol=1e-6)
    for A, V_level in zip(h.adjacency, h.vertices):
        assert A.shape == (len(V_level),) * 2 and (A != A.T).nnz == 0


def test_spirals_start_at_their_vertex_and_reach_the_one_ring(icosphere_path):
    V, F = meshgnn.read_mesh(icosphere_path)
    h = meshgnn.mesh_hierarchy(V, F, factors=(4,), spiral_length=[9, 5], dilation=1)
    assert [s.shape for s in h.spirals] == [(162, 9), (42, 5)]
    for spirals, A in zip(h.spirals, h.adjacency):
        assert spirals.dtype == np.int64
        np.testing.assert_array_equal(spirals[:, 0], np.arange(len(spirals)))
        # Entries 1..valence are the 1-ring (valence 5 or 6 on an icosphere).
        for v in range(len(spirals)):
            ring = set(A[v].indices)
            assert set(spirals[v, 1 : 1 + min(len(ring), spirals.shape[1] - 1)]) <= ring
    assert (h.padded_spirals(0) == h.spirals[0]).all()  # a closed sphere has no padding


def test_any_number_of_levels_uses_the_default_spirals(icosphere_path):
    V, F = meshgnn.read_mesh(icosphere_path)
    for factors in [(2,), (2, 2), (2, 2, 2)]:
        h = meshgnn.mesh_hierarchy(V, F, factors=factors)
        assert len(h.vertices) == len(h.spirals) == len(factors) + 1
        assert len(h.down) == len(h.up) == len(factors)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"factors": (0.5,)}, "factor 0 is 0.5"),
        ({"factors": (4,), "spiral_length": [9, 9, 9]}, "spiral_length: give one value"),
        ({"factors": (4,), "dilation": 0}, "dilation: every value must be an integer >= 1"),
        ({"factors": (400,)}, "mesh_hierarchy"),
    ],
)
def test_bad_hierarchy_requests_raise(icosphere_path, kwargs, message):
    V, F = meshgnn.read_mesh(icosphere_path)
    with pytest.raises(ValueError) as error:
        meshgnn.mesh_hierarchy(V, F, **kwargs)
    assert message in str(error.value)


def test_a_non_manifold_template_is_refused():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, -1, 0], [1, 1, 1]], np.float32)
    F = np.array([[0, 1, 2], [0, 1, 3], [0, 1, 4], [2, 3, 5]])  # edge 0-1 has three faces
    with pytest.raises(ValueError) as error:
        meshgnn.mesh_hierarchy(V, F, factors=(2,))
    assert "mesh_hierarchy" in str(error.value)
