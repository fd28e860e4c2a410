"""The kernel's layout on the ground floor, ``ident.kernel_layout`` (issue 28): the one home of the split
of R into Q_i and P_i, the rows of Phi H, sigma_min(P_ell), the chart P_ell = I and state space <-> kernel
on arrays. Each function is checked against what it means (a product with the Hankel matrix, a
trajectory, the python-control conversion), not against a copy of its code."""
from __future__ import annotations

import numpy as np
import pytest

from ident import kernel_layout
from ident.hankel import block_hankel, time_major_permutation
from ident.representations import kernel_to_ss, p_ell_condition, random_system, simulate, ss_to_kernel
from ident.structure import Structure

EPS = np.finfo(float).eps


def arrays(system):
    return [np.asarray(x, dtype=float) for x in (system.A, system.B, system.C, system.D)]


def test_split_and_join_are_inverse_and_follow_the_time_major_columns() -> None:
    rng = np.random.default_rng(1)
    m, p, ell = 2, 3, 2
    R = rng.standard_normal((p, (ell + 1) * (m + p)))
    Q, P = kernel_layout.split_kernel(R, m, ell)
    assert Q.shape == (ell + 1, p, m) and P.shape == (ell + 1, p, p)
    for lag in range(ell + 1):  # column lag q + i of R is variable i at that lag; outputs negated into P
        first = lag * (m + p)
        assert np.array_equal(Q[lag], R[:, first:first + m]) and np.array_equal(P[lag], -R[:, first + m:first + m + p])
    assert np.array_equal(kernel_layout.join_kernel(Q, P), R)  # data movement only: exact


def test_hankel_rows_name_the_variable_and_lag_of_each_row_of_phi_h() -> None:
    rng = np.random.default_rng(2)
    depths, n_cols = (3, 1, 2), (6, 4)
    perm = rng.permutation(sum(depths))
    structure = Structure(depths, n_cols, perm)
    p = rng.standard_normal(structure.n_params)
    samples, hankel = structure.split(p), structure.hankel(p)
    variables, lags = kernel_layout.hankel_rows(depths, perm)
    for k, (i, lag) in enumerate(zip(variables, lags)):
        expected = np.concatenate([samples[j][i][lag: lag + n_cols[j]] for j in range(len(n_cols))])
        np.testing.assert_array_equal(hankel[k], expected)
    unpermuted = kernel_layout.hankel_rows(depths)
    assert list(unpermuted[0]) == [0, 0, 0, 1, 2, 2] and list(unpermuted[1]) == [0, 1, 2, 0, 0, 1]


def test_time_major_columns_put_a_time_major_kernel_on_phi_h() -> None:
    rng = np.random.default_rng(3)
    n_vars, ell, T = 3, 2, 20
    w = rng.standard_normal((T, n_vars))
    R = rng.standard_normal((2, (ell + 1) * n_vars))
    perm = rng.permutation((ell + 1) * n_vars)
    structure = Structure((ell + 1,) * n_vars, (T - ell,), perm)
    columns = kernel_layout.time_major_columns(structure.depths, structure.perm)
    on_phi_h = R[:, columns] @ structure.hankel(structure.params_from_series([w]))
    np.testing.assert_allclose(on_phi_h, R @ block_hankel(w, ell + 1), rtol=0, atol=50 * EPS * np.abs(R).sum() * np.abs(w).max())
    time_major = Structure.time_major(n_vars, ell, [T - ell])
    assert list(kernel_layout.time_major_columns(time_major.depths, time_major.perm)) == list(range((ell + 1) * n_vars))
    assert list(time_major.perm) == list(time_major_permutation(n_vars, ell + 1))


def test_p_ell_distance_is_a_property_of_the_model_not_of_its_parameter() -> None:
    rng = np.random.default_rng(4)
    m, p, ell = 1, 2, 2
    R = kernel_layout.in_chart(rng.standard_normal((p, (ell + 1) * (m + p))))
    S = rng.standard_normal((p, p)) * 1e3  # another parameter of the same model
    distance = kernel_layout.p_ell_distance(R, m, ell)
    assert abs(kernel_layout.p_ell_distance(S @ R, m, ell) - distance) <= 1e3 * np.linalg.cond(S) * EPS
    assert abs(p_ell_condition(R, m, ell) * distance - 1) <= 1e3 * EPS
    rows = np.linalg.svd(R, full_matrices=False)[2]  # the definition: sigma_min of the last p columns
    assert abs(np.linalg.svd(rows[:, -p:], compute_uv=False)[-1] - distance) <= 1e3 * EPS
    singular = R.copy()
    singular[:, -p:] = 0.0  # P_ell = 0: no output at lag ell
    assert kernel_layout.p_ell_distance(singular, m, ell) <= 10 * EPS


def test_in_chart_gives_the_same_model_with_p_ell_the_identity() -> None:
    rng = np.random.default_rng(5)
    p, width = 2, 9
    R = rng.standard_normal((p, width))
    given = R.copy()
    normal = kernel_layout.in_chart(R)
    scale = np.linalg.cond(R[:, -p:])
    np.testing.assert_allclose(normal[:, -p:], -np.eye(p), rtol=0, atol=100 * scale * EPS)
    # R = P_ell (P_ell^{-1} R) with P_ell = -R[:, -p:]: the same rows, the same model
    np.testing.assert_allclose(R[:, -p:] @ normal, -R, rtol=0, atol=100 * scale * EPS * np.abs(R).max() * width)
    assert np.array_equal(R, given) and not np.shares_memory(normal, R)  # the caller's array untouched


@pytest.mark.parametrize("m, p, ell", [(1, 1, 3), (2, 2, 2), (0, 2, 1), (2, 1, 1)])
def test_state_space_kernel_annihilates_the_trajectories_and_agrees_with_ss_to_kernel(m, p, ell) -> None:
    rng = np.random.default_rng(10 * m + p + ell)
    system = random_system(m, p, ell, rng=rng)
    R = kernel_layout.state_space_kernel(*arrays(system), ell)
    u = rng.standard_normal((60, m))
    w = np.hstack([u, simulate(system, u, rng.standard_normal(ell * p))])
    residual = R @ block_hankel(w, ell + 1)
    assert np.abs(residual).max() <= 1e4 * EPS * np.abs(R).max() * np.abs(w).max() * R.shape[1]
    np.testing.assert_allclose(kernel_layout.in_chart(R), ss_to_kernel(system, ell), rtol=0,
                               atol=1e6 * EPS * max(1.0, np.abs(ss_to_kernel(system, ell)).max()))


@pytest.mark.parametrize("m, p, ell", [(1, 2, 2), (0, 1, 3), (2, 1, 0)])
def test_observer_form_and_reading_the_kernel_off_it_are_inverse(m, p, ell) -> None:
    rng = np.random.default_rng(20 + m + p + ell)
    R = kernel_layout.in_chart(rng.standard_normal((p, (ell + 1) * (m + p))))
    A, B, C, D = kernel_layout.observer_form(*kernel_layout.split_kernel(R, m, ell))
    model = kernel_to_ss(R, m, ell)
    for ours, theirs in zip((A, B, C, D), arrays(model)):
        np.testing.assert_array_equal(ours, theirs)  # kernel_to_ss is this realisation wrapped
    back = kernel_layout.observer_form_kernel(A, B, C, D, ell)
    if ell == 0:
        assert back is None  # no state to read the kernel off
    else:
        np.testing.assert_allclose(back, R, rtol=0, atol=1e3 * EPS * np.abs(R).max() ** 2)


def test_observability_rows_and_the_block_toeplitz_matrix() -> None:
    rng = np.random.default_rng(6)
    A, C = rng.standard_normal((3, 3)) / 3, rng.standard_normal((2, 3))
    O = kernel_layout.observability_rows(A, C, 4)
    for j in range(4):
        np.testing.assert_allclose(O[2 * j: 2 * j + 2], C @ np.linalg.matrix_power(A, j), rtol=1e-12, atol=1e-14)
    H = rng.standard_normal((3, 2, 1))
    T = kernel_layout.block_toeplitz(H, 3)
    assert np.array_equal(T[4:6, 0:1], H[2]) and np.array_equal(T[2:4, 1:2], H[0]) and not T[0:2, 1:3].any()


def test_kernel_blocks_are_views_of_the_time_major_blocks_and_blocks_kernel_is_the_inverse() -> None:
    rng = np.random.default_rng(9)
    for m, p, ell in [(0, 1, 0), (1, 1, 3), (2, 3, 2)]:
        q = m + p
        R = rng.standard_normal((p, (ell + 1) * q))
        blocks = kernel_layout.kernel_blocks(R, ell)
        assert blocks.shape == (ell + 1, p, q) and np.shares_memory(blocks, R)
        for lag in range(ell + 1):
            assert np.array_equal(blocks[lag], R[:, lag * q:(lag + 1) * q])
        assert np.array_equal(kernel_layout.blocks_kernel(blocks), R)  # data movement only: exact
        Q, P = kernel_layout.split_kernel(R, m, ell)
        assert np.array_equal(blocks[:, :, :m], Q) and np.array_equal(blocks[:, :, m:], -P)
