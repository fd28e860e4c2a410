"""Tests of the initial approximations (ident.starts)."""
import numpy as np
import pytest

from ident import starts
from ident.hankel import block_hankel
from ident.structure import Structure


def arx_data(n_samples=100, seed=0):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n_samples)
    y = np.zeros(n_samples)
    for t in range(n_samples - 2):
        y[t + 2] = 1.2 * y[t + 1] - 0.5 * y[t] + 0.7 * u[t + 1] + 0.2 * u[t]
    return np.column_stack([u, y])


def test_least_squares_kernel_recovers_an_exact_arx_system():
    w = arx_data()
    structure = Structure.time_major(2, 2, [len(w) - 2])
    R = starts.least_squares(structure.params_from_series([w]), structure, 5)
    assert np.allclose(R, [[0.2, -0.5, 0.7, 1.2, 0.0, -1.0]], atol=1e-10 * np.abs(w).max())


def test_least_squares_is_the_regression_of_the_last_rows_on_the_hankel_matrix():
    # the same numbers as the regression written on block_hankel(w) directly (the DAISY runner's start)
    rng = np.random.default_rng(1)
    w = rng.standard_normal((60, 3))
    structure = Structure.time_major(3, 2, [58])
    hankel = block_hankel(w, 3)
    theta = np.linalg.lstsq(hankel[:-2].T, hankel[-2:].T, rcond=None)[0].T
    R = starts.least_squares(structure.params_from_series([w]), structure, 7)
    assert np.array_equal(R, np.hstack([theta, -np.eye(2)]))


def test_unstructured_lra_spans_the_left_null_space_of_exact_data():
    w = arx_data(seed=2)
    structure = Structure.time_major(2, 2, [len(w) - 2])
    p = structure.params_from_series([w])
    R = starts.start("lra", p, structure, 5)
    H = structure.hankel(p)
    assert R.shape == (1, 6) and np.isclose(np.linalg.norm(R), 1.0)
    assert np.linalg.norm(R @ H) <= 1e-12 * np.linalg.norm(H)


def test_triangular_factor_of_several_series_with_a_permutation():
    rng = np.random.default_rng(3)
    structure = Structure((3, 2, 3), (12, 9), perm=tuple(rng.permutation(8)))
    p = rng.standard_normal(structure.n_params)
    F = starts.hankel_triangular_factor(p, structure, chunk=5)  # several chunks per series
    H = structure.hankel(p)
    assert np.allclose(F.T @ F, H @ H.T, rtol=1e-12, atol=1e-12 * np.abs(H).max() ** 2)


def test_default_starts_in_order_and_reproducible():
    w = arx_data(seed=4)
    structure = Structure.time_major(2, 2, [len(w) - 2])
    p = structure.params_from_series([w])
    first = list(starts.default_starts(p, structure, 5))
    second = list(starts.default_starts(p, structure, 5))
    assert [name for name, _ in first] == ["unstructured LRA", "perturbed LRA (eps=0.001)",
                                          "perturbed LRA (eps=0.1)", "least squares [X, -I]"]
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(first, second))


def test_unknown_start_is_named():
    structure = Structure.time_major(2, 1, [10])
    with pytest.raises(ValueError, match="unknown start 'subspace'"):
        starts.start("subspace", np.zeros(structure.n_params), structure, 3)
