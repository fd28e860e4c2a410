"""The refinement on missing samples without the Jacobian (33-banded-missing-data.md): J^T J and J^T r
from the banded factor, and the Levenberg-Marquardt loop on them, against the Jacobian and MINPACK."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize

import ident.banded_misfit as banded_misfit
import ident.incomplete as incomplete
from ident.incomplete import in_chart, kernel_solution, refined_kernel, sparse_solution
from ident.normal_lm import normal_levenberg_marquardt
from ident.representations import random_system, simulate, ss_to_kernel


def gappy_problem(m: int, p: int, ell: int, lengths: list, seed: int, exact: bool = False, scattered: bool = False):
    """(the model's kernel in the chart moved off its minimum, and for each series of the model of the
    given lengths its values with the gaps at 0 and its weights, 15 % of them 0)."""
    rng = np.random.default_rng(seed)
    model = random_system(m, p, ell, rng)
    values, weights = [], []
    for n_samples in lengths:
        u = rng.standard_normal((n_samples, m))
        w = np.hstack([u, simulate(model, u, rng.standard_normal(model.nstates))])
        w += 0.1 * rng.standard_normal(w.shape)
        v = rng.uniform(0.5, 2.0, w.shape) if scattered else np.ones(w.shape)
        v[rng.random(w.shape) < 0.15] = 0.0
        if exact:
            v[:, 0] = np.where(v[:, 0] > 0, np.inf, 0.0)
        values.append(np.where(v == 0, 0.0, w))
        weights.append(v)
    kernel = in_chart(ss_to_kernel(model, ell))
    kernel[:, :-p] += 0.01 * rng.standard_normal(kernel[:, :-p].shape)
    return kernel, values, weights


def relative_gap(a, b) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())


@pytest.mark.parametrize("m, p, ell, seed, exact, scattered", [(2, 2, 2, 0, False, False), (1, 1, 3, 1, False, True),
                                                               (1, 2, 2, 2, True, True), (2, 1, 4, 3, False, False)])
def test_the_normal_equations_are_those_of_the_jacobian(m, p, ell, seed, exact, scattered) -> None:
    """J^T J and J^T r formed block by block from the factor, against J itself (banded): the same sums
    in another order, so equal to a few eps times the sizes of J^T J's entries (the block of
    NORMAL_BLOCK samples is smaller than the series here, so the blocks' seams count too)."""
    kernel, (values,), (weights,) = gappy_problem(m, p, ell, [3 * banded_misfit.NORMAL_BLOCK // 2], seed, exact, scattered)
    solution = kernel_solution(kernel, values, weights, jacobian=True, normal=True)
    gram, gradient = solution.normal_equations()
    jacobian, residuals = solution.jacobian, solution.residuals
    size = np.abs(jacobian).T @ np.abs(jacobian)
    assert np.all(np.abs(gram - jacobian.T @ jacobian) <= 1e3 * np.finfo(float).eps * size)
    gradient_size = np.abs(jacobian).T @ np.abs(residuals)
    assert np.all(np.abs(gradient - jacobian.T @ residuals) <= 1e3 * np.finfo(float).eps * gradient_size)
    assert gram.shape == (p * ((ell + 1) * (m + p) - p),) * 2


def test_the_sparse_fallback_forms_its_normal_equations_from_its_jacobian(monkeypatch) -> None:
    kernel, (values,), (weights,) = gappy_problem(2, 2, 2, [600], 4, scattered=True)
    monkeypatch.setattr(incomplete, "banded_solution", lambda *args: None)  # a zero pivot everywhere
    solution = kernel_solution(kernel, values, weights, normal=True)
    assert solution.jacobian is None  # not asked for: only the closure keeps it
    reference = sparse_solution(kernel, values, weights, jacobian=True)
    gram, gradient = solution.normal_equations()
    assert relative_gap(gram, reference.jacobian.T @ reference.jacobian) < 1e-12
    assert relative_gap(gradient, reference.jacobian.T @ reference.residuals) < 1e-12


def minpack_refinement(kernel0, values, weights, tol: float):
    """The refinement as it was: MINPACK's Levenberg-Marquardt on the residuals and the full Jacobian."""
    p = kernel0.shape[0]

    def solved(theta, jacobian):
        kernel = np.hstack([theta.reshape(p, -1), -np.eye(p)])
        found = [kernel_solution(kernel, w, v, jacobian=jacobian) for w, v in zip(values, weights)]
        return np.concatenate([s.jacobian if jacobian else s.residuals for s in found])

    result = scipy.optimize.least_squares(lambda t: solved(t, False), in_chart(kernel0)[:, :-p].ravel(),
                                          jac=lambda t: solved(t, True), method="lm", xtol=tol, ftol=tol, gtol=tol)
    return np.hstack([result.x.reshape(p, -1), -np.eye(p)]), 2 * result.cost


@pytest.mark.parametrize("seed", [5, 6])
def test_the_refinement_reaches_minpacks_minimum_without_forming_the_jacobian(seed, monkeypatch) -> None:
    """Two series, 15 % missing: the same minimum as MINPACK on the full Jacobian, the misfits equal to
    the tolerance (1e-10, relative) and the kernels to its square root (the minimum's flat directions);
    banded_jacobian, which forms J, is never called."""
    kernel0, values, weights = gappy_problem(2, 2, 2, [1500, 1200], seed)
    reference, reference_misfit = minpack_refinement(kernel0, values, weights, 1e-10)

    def refused(*args):
        raise AssertionError("the refinement formed the Jacobian")
    monkeypatch.setattr(banded_misfit, "banded_jacobian", refused)
    kernel, fit = refined_kernel(kernel0, values, weights, 100, 1e-10)
    misfit = sum(np.sum(kernel_solution(kernel, w, v).residuals ** 2) for w, v in zip(values, weights))
    assert fit.status > 0 and fit.njev <= fit.nfev <= 100
    assert abs(misfit - reference_misfit) <= 1e-9 * reference_misfit
    assert abs(fit.cost - misfit) <= 1e-12 * misfit
    assert relative_gap(kernel, reference) < 1e-4


def rosenbrock(x):
    return np.array([10 * (x[1] - x[0] ** 2), 1 - x[0]])


def rosenbrock_evaluation(x):
    r = rosenbrock(x)
    jacobian = np.array([[-20 * x[0], 10.0], [-1.0, 0.0]])
    return float(r @ r), lambda: (jacobian.T @ jacobian, jacobian.T @ r)


def test_the_loop_finds_rosenbrocks_minimum_and_stops_by_the_rules() -> None:
    fit = normal_levenberg_marquardt(rosenbrock_evaluation, np.array([-1.2, 1.0]), 1e-12, 200)
    assert fit.status > 0 and np.abs(fit.x - 1.0).max() < 1e-6 and fit.cost < 1e-20
    at_minimum = normal_levenberg_marquardt(rosenbrock_evaluation, np.array([1.0, 1.0]), 1e-12, 200)
    assert (at_minimum.status, at_minimum.nfev, at_minimum.njev) == (1, 1, 1)  # r = 0: gtol at once
    short = normal_levenberg_marquardt(rosenbrock_evaluation, np.array([-1.2, 1.0]), 1e-12, 3)
    assert short.status == 0 and short.nfev == 3 and short.njev <= 3


def test_a_trial_that_is_not_finite_is_a_rejected_step() -> None:
    def evaluation(x):  # infinite misfit beyond x = 0.5: the minimum of (x - 1)^2 is out of reach
        cost, normal = float((x[0] - 1) ** 2), lambda: (np.array([[1.0]]), np.array([x[0] - 1]))
        return (cost if x[0] <= 0.5 else np.inf), normal
    fit = normal_levenberg_marquardt(evaluation, np.array([0.0]), 1e-10, 200)
    assert np.isfinite(fit.cost) and 0.0 < fit.x[0] <= 0.5


def test_a_solution_with_its_normal_equations_is_freed_without_the_collector() -> None:
    """The closure holds the factor, not the solution: a reference cycle would keep the band (the
    largest array of an evaluation) alive until the cyclic collector runs, two bands at once in ident."""
    import gc
    import weakref
    kernel, (values,), (weights,) = gappy_problem(1, 1, 2, [1200], 7)
    gc.disable()
    try:
        found = banded_misfit.banded_solution(kernel, values, weights, normal=True)
        assert found is not None and found.normal_equations is not None
        alive = weakref.ref(found)
        del found
        assert alive() is None
        solution = kernel_solution(kernel, values, weights, normal=True)
        alive = weakref.ref(solution)
        del solution
        assert alive() is None
    finally:
        gc.enable()
