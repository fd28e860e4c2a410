"""Optimisers by name (issue 28, deliverable 3): ``slra(..., optimiser=NAME)`` dispatches through the
registry ``ident.solver.OPTIMISERS`` to a callable of one signature, ``Optimiser`` (26-solver-optimiser.md);
the default, "lm", is the Levenberg-Marquardt iteration, with the same result as before bit for bit."""
from __future__ import annotations

import numpy as np
import pytest

from ident.solver import OPTIMISERS, InfeasibleKernelError, Optimiser, Settings, register_optimiser, slra
from ident.solver.optimiser import levenberg_marquardt
from ident.structure import Structure, series_to_parameters


def noisy_problem(seed: int = 3):
    """Parameters and structure of a noisy trajectory of a second-order SISO system (ell = 2, rank 5)."""
    rng = np.random.default_rng(seed)
    T = 120
    u = rng.standard_normal(T)
    y = np.zeros(T)
    for t in range(2, T):
        y[t] = 1.5 * y[t - 1] - 0.7 * y[t - 2] + u[t - 1] + 0.5 * u[t - 2]
    w = np.column_stack([u, y]) + 0.05 * rng.standard_normal((T, 2))
    structure = Structure((3, 3), (T - 2,))
    return series_to_parameters([w]), structure, 5


@pytest.fixture
def recording():
    """An optimiser registered as "recording" for the test: Levenberg-Marquardt, with its calls kept."""
    calls = []

    def recording_optimiser(problem, initial_kernel, settings, disp):
        calls.append((problem, np.array(initial_kernel), settings, disp))
        return levenberg_marquardt(problem, initial_kernel, settings, disp)

    register_optimiser("recording", recording_optimiser)
    try:
        yield calls
    finally:
        del OPTIMISERS["recording"]


def test_the_default_is_levenberg_marquardt_and_naming_it_changes_nothing() -> None:
    assert OPTIMISERS["lm"] is levenberg_marquardt and isinstance(levenberg_marquardt, Optimiser)
    p, structure, rank = noisy_problem()
    default, named = slra(p, structure, rank), slra(p, structure, rank, optimiser="lm")
    assert default.iterations > 1 and default.status.converged
    assert np.array_equal(default.R, named.R) and np.array_equal(default.p_hat, named.p_hat)
    assert default.misfit == named.misfit and default.history == named.history  # the same code path: exact


def test_a_registered_optimiser_is_called_with_the_documented_arguments(recording) -> None:
    p, structure, rank = noisy_problem()
    reference = slra(p, structure, rank, maxiter=40, tol=1e-7)
    result = slra(p, structure, rank, maxiter=40, tol=1e-7, optimiser="recording")
    assert len(recording) == 1
    problem, initial_kernel, settings, disp = recording[0]
    assert isinstance(settings, Settings) and (settings.maxiter, settings.tol) == (40, 1e-7) and disp == "off"
    assert initial_kernel.shape == (structure.n_rows - rank, structure.n_rows)
    assert problem.structure is structure
    assert np.array_equal(result.R, reference.R) and result.misfit == reference.misfit


def test_an_infeasible_start_reported_by_the_optimiser_sends_slra_to_the_next_start() -> None:
    calls = []

    def refuses_the_first_start(problem, initial_kernel, settings, disp):
        calls.append(initial_kernel)
        if len(calls) == 1:
            raise InfeasibleKernelError("Gamma is singular at this kernel (the test says so)")
        return levenberg_marquardt(problem, initial_kernel, settings, disp)

    register_optimiser("refuses the first start", refuses_the_first_start)
    try:
        p, structure, rank = noisy_problem()
        result = slra(p, structure, rank, optimiser="refuses the first start")
    finally:
        del OPTIMISERS["refuses the first start"]
    assert len(calls) == 2 and not np.array_equal(calls[0], calls[1])
    assert "started from a fall-back after" in result.message and "the test says so" in result.message
    assert result.status.converged
