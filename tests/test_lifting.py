"""The lifted start of ident for a periodic pattern of missing samples (32-missing-data.md)."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from ident import ident
from ident.lifting import gap_period, lifted_kernel, realisation
from ident.representations import kernel_to_ss, markov_parameters, random_system, simulate


def h2_error(true, found, k: int = 2000) -> float:
    a, b = np.asarray(markov_parameters(true, k)), np.asarray(markov_parameters(found, k))
    return float(np.linalg.norm(a - b) / np.linalg.norm(a))


def periodic_data(seed: int, m: int = 1, p: int = 1, ell: int = 5, T: int = 200, period: int = 2):
    """Exact data of a random stable system, the first output missing at every phase but the first."""
    rng = np.random.default_rng(seed)
    system = random_system(m, p, ell, rng)
    u = rng.standard_normal((T, m))
    w = np.hstack([u, simulate(system, u, rng.standard_normal(ell * p))])
    gappy = w.copy()
    for phase in range(1, period):
        gappy[phase::period, m] = np.nan
    return system, w, gappy


def test_gap_period_finds_the_least_period() -> None:
    weights = np.ones((12, 2))
    weights[1::2, 1] = 0
    assert gap_period([weights], 1) == 2
    weights = np.ones((13, 2))
    weights[1::3, 1] = weights[2::3, 1] = 0
    assert gap_period([weights], 1) == 3
    assert gap_period([weights, weights[:10]], 1) == 3  # phases from each series' first sample


def test_gap_period_refuses_what_is_not_a_periodic_pattern_of_outputs() -> None:
    complete = np.ones((12, 2))
    assert gap_period([complete], 1) is None  # nothing missing
    random_gaps = np.ones((40, 2))
    random_gaps[[3, 4, 11, 30], 1] = 0
    assert gap_period([random_gaps], 1) is None
    input_gaps = np.ones((12, 2))
    input_gaps[1::2, 0] = 0
    assert gap_period([input_gaps], 1) is None  # an input missing: the lifted inputs are not all known
    other = np.ones((12, 2))
    other[0::2, 1] = 0
    every_other = np.ones((12, 2))
    every_other[1::2, 1] = 0
    assert gap_period([every_other, other], 1) is None  # two series, two patterns


def test_realisation_reproduces_the_markov_parameters() -> None:
    system = random_system(2, 2, 2, np.random.default_rng(5))
    markov = np.asarray(markov_parameters(system, 12))
    found = realisation(markov, 4)
    scale = np.abs(markov).max()
    assert np.abs(np.asarray(markov_parameters(found, 40)) - np.asarray(markov_parameters(system, 40))).max() \
        < 1e-10 * scale


@pytest.mark.parametrize("seed", [4, 14])  # systems where every default start stops in a local minimum
def test_the_lifted_start_is_the_model_on_exact_data(seed: int) -> None:
    system, _, gappy = periodic_data(seed)
    weights = np.where(np.isnan(gappy), 0.0, 1.0)
    kernel = lifted_kernel(ident, [np.nan_to_num(gappy)], [weights], 1, 5)
    assert h2_error(system, kernel_to_ss(kernel, 1, 5, cond_warn=np.inf)) < 1e-8
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sysh, info, wh, _ = ident(gappy, 1, 5)
        others = ident(gappy, 1, 5, init=["lra", "arx"])[1]
    assert "lifted" in [c.start for c in info.candidates]
    assert "lifted" not in [c.start for c in others.candidates]  # only beside the default starts
    assert h2_error(system, sysh) < 1e-8


def test_a_period_of_three_with_two_outputs() -> None:
    """Period 3, the first output observed at one phase in three, the second at every sample."""
    system, w, gappy = periodic_data(11, m=1, p=2, ell=2, T=300, period=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sysh, info, wh, _ = ident(gappy, 1, 2)
    assert "lifted" in [c.start for c in info.candidates]
    assert h2_error(system, sysh) < 1e-8
    assert np.abs(wh - w).max() < 1e-8 * np.abs(w).max()


def test_noisy_periodic_data_still_give_a_start() -> None:
    system, w, _ = periodic_data(3)
    noisy = w + 0.01 * np.random.default_rng(1).standard_normal(w.shape)
    noisy[1::2, 1] = np.nan
    before = noisy.copy()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sysh, info, _, _ = ident(noisy, 1, 5)
    lifted = [c for c in info.candidates if c.start == "lifted"]
    assert lifted and not lifted[0].error
    assert h2_error(system, sysh) < 0.05  # a noisy estimate (noise 1 % of the data), not the model itself
    np.testing.assert_array_equal(noisy, before)  # the caller's data untouched


def test_no_lifted_start_without_inputs() -> None:
    """An autonomous model has no impulse response to realise: its periodic gaps get the default starts only."""
    rng = np.random.default_rng(8)
    system = random_system(1, 1, 3, rng)
    y = simulate(system, np.zeros((120, 1)), rng.standard_normal(3))
    y[1::2] = np.nan
    assert gap_period([np.where(np.isnan(y), 0.0, 1.0)], 0) is None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        info = ident(y, 0, 3)[1]
    assert "lifted" not in [c.start for c in info.candidates]
