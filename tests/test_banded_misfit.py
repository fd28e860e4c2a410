"""The misfit with gaps by the banded saddle-point system (33-banded-missing-data.md): it answers for the
smoother of 16-misfit.md on long series with gaps, and agrees with it and with the sparse system."""
from __future__ import annotations

import numpy as np
import pytest

import ident.smoothing as smoothing
from ident import misfit
from ident.banded_misfit import BANDED_FROM, banded_solution, gap_kernel, gram_solution
from ident.incomplete import in_chart, sparse_solution
from ident.representations import make_ss, random_system, simulate, ss_to_kernel
from ident.smoothing import smoothed_misfit


def noisy_series(m: int, p: int, ell: int, n_samples: int, noise: float, seed: int):
    rng = np.random.default_rng(seed)
    model = random_system(m, p, ell, rng)
    u = rng.standard_normal((n_samples, m))
    w = np.hstack([u, simulate(model, u, rng.standard_normal(model.nstates))])
    return model, w + noise * rng.standard_normal(w.shape), rng


def gap_pattern(shape, kind: str, rng) -> np.ndarray:
    """Where values are missing: at random, in bursts, or half of the outputs."""
    if kind == "random":
        return rng.random(shape) < 0.1
    if kind == "bursts":  # runs of up to 5 samples of one variable
        gaps = np.zeros(shape, bool)
        for start, variable in zip(rng.integers(0, shape[0] - 5, shape[0] // 40), rng.integers(0, shape[1], shape[0] // 40)):
            gaps[start:start + rng.integers(1, 6), variable] = True
        return gaps
    gaps = np.zeros(shape, bool)
    gaps[:, -1] = rng.random(shape[0]) < 0.5
    return gaps


@pytest.fixture
def banded_answers(monkeypatch):
    """How many series the banded system answered (not None) in the calls made under the fixture."""
    answered = []
    original = smoothing.gappy_misfit

    def spy(*args):
        found = original(*args)
        answered.append(found is not None)
        return found

    monkeypatch.setattr(smoothing, "gappy_misfit", spy)
    return answered


@pytest.mark.parametrize("m, p, ell, kind, seed", [(2, 2, 2, "random", 0), (1, 1, 3, "random", 1), (1, 2, 2, "bursts", 2),
                                                   (2, 2, 2, "outputs", 3), (2, 1, 4, "bursts", 4)])
def test_the_banded_system_answers_as_the_smoother_on_random_gaps(m, p, ell, kind, seed, banded_answers) -> None:
    """To the smoother's own accuracy: it holds its factor once that changes by less than
    STATIONARY_TOL = 1e-10 a sample, which moves its misfit by up to about 1e-9 (7e-10 on the last
    case, where the sparse system and dense least squares agree with the banded one to 1e-15)."""
    model, w, rng = noisy_series(m, p, ell, BANDED_FROM + 200, 0.1, seed)
    gappy = np.where(gap_pattern(w.shape, kind, rng), np.nan, w)
    A, B, C, D = (np.asarray(getattr(model, x), dtype=float) for x in "ABCD")
    smoothed = smoothed_misfit(A, B, C, D, [gappy], banded=False)
    M, wh, xini = misfit(gappy, model)
    assert banded_answers == [True]
    size = np.abs(w).max()
    assert abs(M - smoothed.misfit) <= 1e-8 * smoothed.misfit
    sparse = sparse_solution(in_chart(ss_to_kernel(model, ell)), np.nan_to_num(gappy), np.where(np.isnan(gappy), 0.0, 1.0))
    assert abs(M - np.sum(sparse.residuals ** 2)) <= 1e-10 * M
    assert np.abs(wh - smoothed.trajectories[0]).max() <= 1e-10 * size
    assert np.abs(xini - smoothed.initial_states).max() <= 1e-8 * max(np.abs(smoothed.initial_states).max(), 1.0)
    assert np.array_equal(np.isnan(gappy), np.isnan(gappy) & ~np.isfinite(gappy))  # gaps left in the caller's data


def test_several_series_mix_the_banded_system_and_the_smoother(banded_answers) -> None:
    model, w, rng = noisy_series(2, 2, 2, 2 * BANDED_FROM, 0.1, 5)
    long = np.where(rng.random((BANDED_FROM, 4)) < 0.1, np.nan, w[:BANDED_FROM])
    short = np.where(rng.random((300, 4)) < 0.1, np.nan, w[BANDED_FROM:BANDED_FROM + 300])
    complete = w[BANDED_FROM + 300:]
    A, B, C, D = (np.asarray(getattr(model, x), dtype=float) for x in "ABCD")
    smoothed = smoothed_misfit(A, B, C, D, [long, short, complete], banded=False)
    M, wh, xini = misfit([long, short, complete], model)
    assert banded_answers == [True]  # only the long series with gaps
    assert abs(M - smoothed.misfit) <= 1e-10 * smoothed.misfit
    for found, expected in zip(wh, smoothed.trajectories):
        assert np.abs(found - expected).max() <= 1e-10 * np.abs(w).max()


def test_exact_data_stay_with_the_smoother(banded_answers) -> None:
    """On exact data the kernel's equations would see the misfit through rounding (see the text)."""
    model, w, rng = noisy_series(2, 2, 2, BANDED_FROM, 0.0, 6)
    gappy = np.where(rng.random(w.shape) < 0.1, np.nan, w)
    M, wh, _ = misfit(gappy, model)
    assert banded_answers == [False]
    assert M <= 1e-20 * np.nansum(gappy ** 2)
    assert np.abs(wh - w).max() <= 1e-8 * np.abs(w).max()


@pytest.mark.parametrize("options", [{"exct": [0]}, {"wini": 0}])
def test_exact_variables_and_initial_conditions_keep_the_smoother(options, banded_answers) -> None:
    model, w, rng = noisy_series(2, 2, 2, BANDED_FROM, 0.1, 7)
    gappy = np.where(rng.random(w.shape) < 0.1, np.nan, w)
    if "exct" in options:
        gappy[:, 0] = w[:, 0]
    misfit(gappy, model, **options)
    assert banded_answers == []


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_banded_system_solves_the_sparse_saddle_point_system(seed) -> None:
    """Random weights, zeros (missing) and infinities (exact) included: the same residuals, wh and
    Jacobian as the sparse system."""
    model, w, rng = noisy_series(2, 2, 2, 400, 0.1, 10 + seed)
    weights = rng.uniform(0.2, 5.0, w.shape)
    weights[rng.random(w.shape) < 0.15] = 0.0
    weights[:, 0][rng.random(len(w)) < 0.2] = np.inf
    values = np.where(weights == 0, 0.0, w)
    kernel = in_chart(ss_to_kernel(model, 2))
    sparse = sparse_solution(kernel, values, weights, jacobian=True)
    found = banded_solution(kernel, values, weights, jacobian=True)
    residuals, wh = found.residuals, found.approximation
    assert abs(np.sum(residuals ** 2) - np.sum(sparse.residuals ** 2)) <= 1e-10 * np.sum(sparse.residuals ** 2)
    assert np.abs(wh - sparse.approximation).max() <= 1e-10 * np.abs(w).max()
    exact = np.isinf(weights)
    assert np.abs(wh[exact] - w[exact]).max() <= 1e-14 * np.abs(w).max()
    assert found.jacobian.shape == sparse.jacobian.shape == (np.sum((weights > 0) & ~exact), 20)
    assert np.abs(found.jacobian - sparse.jacobian).max() <= 1e-10 * np.abs(sparse.jacobian).max()


def test_the_banded_system_is_least_squares_over_the_trajectories() -> None:
    """Against dense least squares over (x(1), u): the misfit and wh, with bursts of gaps."""
    model, w, rng = noisy_series(2, 1, 4, 300, 0.1, 9)
    gaps = gap_pattern(w.shape, "bursts", rng)
    n_samples, n_states = len(w), model.nstates
    A, B, C, D = (np.asarray(getattr(model, x), dtype=float) for x in "ABCD")
    basis = np.zeros((n_samples, 3, n_states + 2 * n_samples))  # wh(t) as a function of (x(1), u)
    x = np.hstack([np.eye(n_states), np.zeros((n_states, 2 * n_samples))])
    for t in range(n_samples):
        u = np.zeros((2, basis.shape[2]))
        u[:, n_states + 2 * t:n_states + 2 * t + 2] = np.eye(2)
        basis[t, :2], basis[t, 2:] = u, C @ x + D @ u
        x = A @ x + B @ u
    basis = basis.reshape(-1, basis.shape[2])
    seen = ~gaps.ravel()
    coefficients = np.linalg.lstsq(basis[seen], w.ravel()[seen], rcond=None)[0]
    expected_wh = (basis @ coefficients).reshape(w.shape)
    expected_M = np.sum((w.ravel()[seen] - (basis @ coefficients)[seen]) ** 2)
    found = banded_solution(gap_kernel(A, B, C, D)[0], np.where(gaps, 0.0, w), np.where(gaps, 0.0, 1.0))
    residuals, wh = found.residuals, found.approximation
    assert abs(np.sum(residuals ** 2) - expected_M) <= 1e-10 * expected_M
    assert np.abs(wh - expected_wh).max() <= 1e-10 * np.abs(w).max()


def test_a_model_without_a_kernel_of_p_rows_keeps_the_smoother() -> None:
    """n = 3 with two outputs: observability indices 2 and 1, no kernel of lag n / p."""
    rng = np.random.default_rng(8)
    A = np.diag([0.5, -0.3, 0.8])
    B, C, D = rng.standard_normal((3, 1)), rng.standard_normal((2, 3)), rng.standard_normal((2, 1))
    assert gap_kernel(A, B, C, D) is None
    assert gap_kernel(*(np.asarray(getattr(random_system(1, 2, 2, rng), x), dtype=float) for x in "ABCD")) is not None


def test_the_smoother_leaves_the_callers_matrices_alone() -> None:
    """balanced() scales its arguments in place; smoothed_misfit gives it copies."""
    A = np.array([[0.5, 0.1], [0.1, 0.3]])
    B, C, D = np.array([[1e6], [1.0]]), np.array([[1e-6, 1.0]]), np.zeros((1, 1))
    before = [M.copy() for M in (A, B, C, D)]
    smoothed_misfit(A, B, C, D, [np.ones((10, 2))])
    assert all(np.array_equal(M, M0) for M, M0 in zip((A, B, C, D), before))
    model = make_ss(A, B, C, D)
    assert np.array_equal(np.asarray(model.A), before[0])


def test_missing_values_the_data_barely_determine_go_to_the_smoother(banded_answers) -> None:
    """Half of all values missing in errors-in-variables data: the ridge's solves do not settle."""
    model, w, rng = noisy_series(2, 2, 2, BANDED_FROM, 0.1, 11)
    gappy = np.where(rng.random(w.shape) < 0.5, np.nan, w)
    A, B, C, D = (np.asarray(getattr(model, x), dtype=float) for x in "ABCD")
    found = banded_solution(gap_kernel(A, B, C, D)[0], np.nan_to_num(gappy), np.where(np.isnan(gappy), 0.0, 1.0))
    assert not found.settled
    M, _, _ = misfit(gappy, model)
    assert banded_answers == [False]
    assert abs(M - smoothed_misfit(A, B, C, D, [gappy], banded=False).misfit) <= 1e-12 * M


def test_kernel_solution_falls_back_to_the_sparse_system_on_a_zero_pivot(monkeypatch) -> None:
    import ident.banded_misfit as banded_misfit
    from ident.incomplete import kernel_solution

    model, w, rng = noisy_series(2, 2, 2, 300, 0.1, 12)
    weights = np.where(rng.random(w.shape) < 0.1, 0.0, 1.0)
    values, kernel = np.where(weights == 0, 0.0, w), in_chart(ss_to_kernel(model, 2))
    expected = sparse_solution(kernel, values, weights, jacobian=True)
    real = banded_misfit.lapack.dgbtrf

    def singular(*args, **kwargs):
        lu, pivots, _ = real(*args, **kwargs)
        return lu, pivots, 1  # as LAPACK reports U(1, 1) = 0

    monkeypatch.setattr(banded_misfit.lapack, "dgbtrf", singular)
    assert banded_solution(kernel, values, weights) is None
    found = kernel_solution(kernel, values, weights, jacobian=True)
    assert np.abs(found.residuals - expected.residuals).max() <= 1e-14 * np.abs(expected.residuals).max()
    assert np.abs(found.jacobian - expected.jacobian).max() <= 1e-14 * np.abs(expected.jacobian).max()


@pytest.mark.parametrize("m, p, ell, kind, seed", [(2, 2, 2, "random", 20), (1, 2, 2, "bursts", 21), (2, 1, 4, "bursts", 22),
                                                   (2, 2, 2, "outputs", 23)])
def test_the_gram_matrix_corrected_solves_the_saddle_point_system(m, p, ell, kind, seed) -> None:
    """The corrections reach the exact system's answer, not the biased one of the weight rho: the same
    residuals and wh as the banded LU, to rounding."""
    model, w, rng = noisy_series(m, p, ell, 3000, 0.1, seed)
    gaps = gap_pattern(w.shape, kind, rng)
    values, weights = np.where(gaps, 0.0, w), np.where(gaps, 0.0, rng.uniform(0.5, 2.0, w.shape))
    kernel = gap_kernel(*(np.asarray(getattr(model, x), dtype=float) for x in "ABCD"))[0]
    found, expected = gram_solution(kernel, values, weights), banded_solution(kernel, values, weights)
    assert found is not None and found.settled and expected.settled
    M, M_expected = np.sum(found.residuals ** 2), np.sum(expected.residuals ** 2)
    assert abs(M - M_expected) <= 1e-12 * M_expected
    assert np.abs(found.approximation - expected.approximation).max() <= 1e-10 * np.abs(w).max()


def test_the_gram_matrix_gives_way_where_the_gaps_are_barely_determined(banded_answers) -> None:
    """Half of all values missing: the corrections do not contract (nor do the LU's ridge solves), and
    the smoother answers, as before the Gram road; an exact value is left to the LU too."""
    model, w, rng = noisy_series(2, 2, 2, BANDED_FROM, 0.1, 11)
    gappy = np.where(rng.random(w.shape) < 0.5, np.nan, w)
    A, B, C, D = (np.asarray(getattr(model, x), dtype=float) for x in "ABCD")
    kernel = gap_kernel(A, B, C, D)[0]
    assert gram_solution(kernel, np.nan_to_num(gappy), np.where(np.isnan(gappy), 0.0, 1.0)) is None
    M, _, _ = misfit(gappy, model)
    assert banded_answers == [False]
    assert abs(M - smoothed_misfit(A, B, C, D, [gappy], banded=False).misfit) <= 1e-12 * M
    weights = np.where(np.isnan(gappy), 0.0, 1.0)
    weights[0, 0] = np.inf
    assert gram_solution(kernel, np.nan_to_num(gappy), weights) is None


def test_the_gram_matrix_answers_where_the_ridge_did_not_settle(banded_answers) -> None:
    """A fifth of the values missing: some gaps are determined only weakly, the LU's four ridge solves
    do not settle, the corrections do; the misfit is the smoother's and the sparse system's."""
    model, w, rng = noisy_series(2, 2, 2, 5000, 0.1, 30)
    gappy = np.where(rng.random(w.shape) < 0.2, np.nan, w)
    A, B, C, D = (np.asarray(getattr(model, x), dtype=float) for x in "ABCD")
    kernel, values, weights = gap_kernel(A, B, C, D)[0], np.nan_to_num(gappy), np.where(np.isnan(gappy), 0.0, 1.0)
    found = gram_solution(kernel, values, weights)
    assert found is not None and found.settled and not banded_solution(kernel, values, weights).settled
    M, wh, _ = misfit(gappy, model)
    assert banded_answers == [True]
    sparse = sparse_solution(in_chart(ss_to_kernel(model, 2)), values, weights)
    assert abs(M - np.sum(sparse.residuals ** 2)) <= 1e-10 * M
    assert abs(M - smoothed_misfit(A, B, C, D, [gappy], banded=False).misfit) <= 1e-8 * M
