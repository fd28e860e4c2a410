"""Property-based tests (hypothesis) of ident and misfit.

Profiles: the default "fast" runs a few examples per property (CI); HYPOTHESIS_PROFILE=thorough runs
many more.
"""
from __future__ import annotations

import os

import control
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ident import ident, misfit
from ident.representations import random_system, simulate

settings.register_profile("fast", max_examples=8, deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("thorough", max_examples=150, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "fast"))

model_classes = st.tuples(st.integers(0, 2), st.integers(1, 2), st.integers(0, 2))  # m, p, ell
seeds = st.integers(0, 2**32 - 1)


def data(m: int, p: int, ell: int, seed: int, noise: float, n_samples: int = 0):
    rng = np.random.default_rng(seed)
    sys = random_system(m, p, ell, rng)
    n_samples = n_samples or 30 + 15 * (ell + 1) * (m + p)
    u = rng.standard_normal((n_samples, m))
    w = np.hstack([u, simulate(sys, u, rng.standard_normal(sys.nstates))])
    return sys, w + noise * rng.standard_normal(w.shape), rng


@given(model_classes, seeds)
def test_exact_trajectories_are_recovered(model_class, seed) -> None:
    m, p, ell = model_class
    sys, w, _ = data(m, p, ell, seed, noise=0.0)
    _, info, wh, _ = ident(w, m, ell)
    assert info.M <= 1e-12 * np.sum(w ** 2)


@given(model_classes, seeds, st.randoms(use_true_random=False))
def test_optimal_misfit_is_invariant_to_permuting_the_variables(model_class, seed, random) -> None:
    m, p, ell = model_class
    _, w, _ = data(m, p, ell, seed, noise=0.1)
    q = m + p
    # the property is about the optimal misfit: the first run must reach a minimum. Some small
    # problems creep for more than the default 100 iterations (autonomous, m = 0, p = 2, ell = 2,
    # seed 364: 112), so the limit is raised and convergence asserted
    _, info, _, _ = ident(w, m, ell, maxiter=500)
    assert info.converged, info.message
    perm = list(range(q))
    random.shuffle(perm)
    # the same model in the permuted variables: permute the kernel's columns within each lag block
    R0 = info.Rh.reshape(p, ell + 1, q)[:, :, perm].reshape(p, (ell + 1) * q)
    _, info_perm, _, _ = ident(w[:, perm], m, ell, sys0=R0, maxiter=500)
    assert info_perm.M == pytest.approx(info.M, rel=1e-6, abs=1e-12)


@given(model_classes, seeds)
def test_misfit_is_invariant_to_a_similarity_transformation(model_class, seed) -> None:
    m, p, ell = model_class
    sys, w, rng = data(m, p, ell, seed, noise=0.2)
    n = sys.nstates
    if n == 0:
        return
    S = rng.standard_normal((n, n)) + 2 * np.sqrt(n) * np.eye(n)
    A, B, C = S @ sys.A @ np.linalg.inv(S), S @ sys.B, sys.C @ np.linalg.inv(S)
    from ident.representations import make_ss
    transformed = make_ss(A, B, C, sys.D)
    assert misfit(w, transformed)[0] == pytest.approx(misfit(w, sys)[0], rel=1e-7)


@given(model_classes, seeds, st.floats(0.01, 100.0))
def test_scaling_the_data_scales_the_misfit_by_c_squared(model_class, seed, c) -> None:
    m, p, ell = model_class
    sys, w, _ = data(m, p, ell, seed, noise=0.2)
    assert misfit(c * w, sys)[0] == pytest.approx(c ** 2 * misfit(w, sys)[0], rel=1e-8)
    _, info, _, _ = ident(w, m, ell)
    _, info_c, _, _ = ident(c * w, m, ell)
    assert info_c.M == pytest.approx(c ** 2 * info.M, rel=1e-5)


@given(model_classes, seeds, st.floats(0.2, 0.8))
def test_splitting_a_series_never_raises_the_misfit_of_a_fixed_model(model_class, seed, fraction) -> None:
    m, p, ell = model_class
    sys, w, _ = data(m, p, ell, seed, noise=0.2)
    cut = max(ell + 1, min(len(w) - ell - 1, int(fraction * len(w))))
    whole = misfit(w, sys)[0]
    pieces = misfit([w[:cut], w[cut:]], sys)[0]
    assert pieces <= whole * (1 + 1e-9) + 1e-12


@given(model_classes, seeds)
def test_misfit_of_the_identified_model_is_its_reported_misfit(model_class, seed) -> None:
    m, p, ell = model_class
    _, w, _ = data(m, p, ell, seed, noise=0.1)
    sysh, info, wh, _ = ident(w, m, ell)
    M, wh_again, _ = misfit(w, sysh)
    assert M == pytest.approx(info.M, rel=1e-6, abs=1e-12)
