"""Error bars of identified models (issue 34, 30-uncertainty-and-stability.md): the contract of
info.uncertainty, the delta method against draws, the noise variance, and singular cases."""
from __future__ import annotations

import warnings

import control
import numpy as np
import pytest

from conftest import recorded_warnings
from ident import UncertaintyWarning, ident, model_uncertainty

PLANT = control.ss(control.tf([0.5, 0.3], [1, -1.2, 0.5], 1))


def second_order_data(seed: int, n_samples: int = 300, noise: float = 0.1, output_error: bool = False):
    """(w, w_true, sigma) of the second-order plant; noise relative to each variable's spread."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n_samples)
    w_true = np.column_stack([u, control.forced_response(PLANT, U=u).outputs])
    sigma = noise * w_true[:, 1].std()
    errors = sigma * rng.standard_normal(w_true.shape)
    if output_error:
        errors[:, 0] = 0
    return w_true + errors, w_true, sigma


def two_by_two_data(seed: int, n_samples: int = 300, noise: float = 0.05):
    rng = np.random.default_rng(seed)
    plant = control.ss([[0.6, 0.2], [0.1, 0.5]], [[1.0, 0.0], [0.3, 1.0]], [[1.0, 0.0], [0.0, 1.0]],
                       np.zeros((2, 2)), 1)
    u = rng.standard_normal((n_samples, 2))
    y = control.forced_response(plant, U=u.T).outputs.T
    w_true = np.column_stack([u, y])
    return w_true + noise * rng.standard_normal(w_true.shape), plant


def test_the_contract_shapes_and_the_order_of_the_poles() -> None:
    w, _ = two_by_two_data(1)
    sysh, info, _, _ = ident(w, 2, 1, uncertainty=True)
    bars = info.uncertainty
    assert bars.std("gain").shape == (2, 2) and bars.std("gain").dtype == float
    poles_std = bars.std("poles")
    assert poles_std.shape == (sysh.nstates,) and np.iscomplexobj(poles_std)
    assert np.array_equal(bars.value("poles"), sysh.poles())  # the same order, the same numbers
    assert np.all(np.isfinite(poles_std.real)) and np.all(poles_std.real > 0)
    gain = np.asarray(control.dcgain(sysh))
    assert np.allclose(bars.value("gain"), gain, rtol=1e-8, atol=1e-10 * np.abs(gain).max())
    omega = np.array([1e-3, 0.5, 2.0])
    assert bars.std("magnitude", omega).shape == (3, 2, 2)
    response = np.array([sysh(np.exp(1j * x)) for x in omega])
    assert np.allclose(bars.value("magnitude", omega), np.abs(response), rtol=1e-8)


def test_real_poles_have_no_imaginary_spread_and_conjugates_share_theirs() -> None:
    w, _, _ = second_order_data(2)
    sysh, info, _, _ = ident(w, 1, 2, uncertainty=True)
    poles, spread = sysh.poles(), info.uncertainty.std("poles")
    pair = np.flatnonzero(poles.imag > 0)[0], np.flatnonzero(poles.imag < 0)[0]
    assert np.isclose(spread[pair[0]].real, spread[pair[1]].real, rtol=1e-4)
    assert np.isclose(spread[pair[0]].imag, spread[pair[1]].imag, rtol=1e-4)
    w2, _ = two_by_two_data(2)
    model2, info2, _, _ = ident(w2, 2, 1, uncertainty=True)
    real = np.abs(model2.poles().imag) == 0
    assert real.any() and np.all(info2.uncertainty.std("poles")[real].imag == 0)


@pytest.mark.parametrize("output_error", [False, True], ids=["eiv", "oe"])
def test_the_delta_method_agrees_with_draws_of_the_parameters(output_error: bool) -> None:
    w, _, _ = second_order_data(3, output_error=output_error)
    _, info, _, _ = ident(w, 1, 2, exct=[0] if output_error else None, uncertainty=True)
    bars = info.uncertainty
    for what in ("gain", "poles"):
        delta = bars.std(what)
        drawn = bars.std(what, method="monte carlo", draws=3000, seed=4)
        # 3000 draws estimate a standard deviation to about 1.3 %; the linearisation adds a little
        assert np.allclose(drawn.real, delta.real, rtol=0.1) and np.allclose(drawn.imag, delta.imag, rtol=0.1)


def test_the_noise_variance_is_estimated_from_the_misfit() -> None:
    w, _, sigma = second_order_data(5, n_samples=3000)
    _, info, _, _ = ident(w, 1, 2, uncertainty=True)
    bars = info.uncertainty
    assert bars.dof == (3000 - 2) - 5  # g K equations, n_theta = 5 free parameters
    assert np.isclose(bars.noise_variance, info.M / bars.dof, rtol=1e-12)
    # M / sigma^2 is chi-square with dof degrees of freedom to first order: its relative spread is sqrt(2 / dof)
    assert abs(bars.noise_variance / sigma ** 2 - 1) < 5 * np.sqrt(2 / bars.dof)


def test_the_spread_of_the_gain_matches_repeated_experiments() -> None:
    gains, predicted = [], []
    for seed in range(40):
        w, _, _ = second_order_data(100 + seed, n_samples=200, output_error=True)
        _, info, _, _ = ident(w, 1, 2, exct=[0], init="lra", uncertainty=True)
        gains.append(info.uncertainty.value("gain")[0, 0])
        predicted.append(info.uncertainty.std("gain")[0, 0])
    # 40 runs estimate a standard deviation to about 11 %: 35 % is three of those
    assert abs(np.std(gains, ddof=1) / np.mean(predicted) - 1) < 0.35


def test_computed_afterwards_it_is_the_same_and_the_data_are_not_modified() -> None:
    w, _, _ = second_order_data(6)
    kept = w.copy()
    sysh, info, _, _ = ident(w, 1, 2, wini=0, exct=[0], uncertainty=True)
    later = model_uncertainty(w, sysh, info, wini=0, exct=[0])
    assert later.dof == 300 - 5  # given initial conditions: T columns
    scale = np.abs(info.uncertainty.covariance).max()
    assert np.allclose(later.covariance, info.uncertainty.covariance, rtol=1e-6, atol=1e-9 * scale)
    assert np.array_equal(w, kept)
    with pytest.raises(ValueError, match="not from an identification on these data"):
        model_uncertainty(w, sysh, info)  # without the options it was identified with


def test_intervals_widen_with_the_level_and_contain_the_value() -> None:
    w, _, _ = second_order_data(7)
    _, info, _, _ = ident(w, 1, 2, uncertainty=True)
    bars = info.uncertainty
    low95, high95 = bars.interval("gain")
    low99, high99 = bars.interval("gain", 0.99)
    assert low99 < low95 < bars.value("gain") < high95 < high99
    width = (high95 - low95) / (2 * bars.std("gain"))
    assert np.isclose(width[0, 0], 1.959964, rtol=1e-5)
    low, high = bars.interval("poles")
    assert np.all(low.real < high.real) and np.all(low.imag < high.imag)


def test_exact_data_have_zero_spread() -> None:
    _, w_true, _ = second_order_data(8, noise=0.0)
    _, info, _, _ = ident(w_true, 1, 2, uncertainty=True)
    assert np.max(np.abs(info.uncertainty.std("poles"))) < 1e-6
    assert info.uncertainty.std("gain")[0, 0] < 1e-6 * abs(info.uncertainty.value("gain")[0, 0])


def test_a_singular_gauss_newton_matrix_gives_infinite_intervals_and_says_why() -> None:
    u = np.ones(100)  # a constant input excites the gain only
    y = control.forced_response(control.ss(control.tf([0.5], [1, -0.5], 1)), U=u).outputs
    w = np.column_stack([u, y + 1e-3 * np.random.default_rng(9).standard_normal(100)])
    with recorded_warnings() as caught:
        _, info, _, _ = ident(w, 1, 1, exct=[0], uncertainty=True)
    messages = [str(c.message) for c in caught if issubclass(c.category, UncertaintyWarning)]
    assert len(messages) == 1 and "singular" in messages[0] and "excite" in messages[0]
    assert "singular" in info.uncertainty.reason
    assert np.all(np.isinf(info.uncertainty.std("gain"))) and np.all(np.isinf(info.uncertainty.std("poles").real))
    assert np.all(np.isinf(info.uncertainty.std("gain", method="monte carlo")))
    with pytest.raises(ValueError, match="no draws: the intervals are infinite"):
        info.uncertainty.draws("gain")


def test_without_uncertainty_nothing_is_computed() -> None:
    w, _, _ = second_order_data(10)
    with warnings.catch_warnings():
        warnings.simplefilter("error", UncertaintyWarning)
        _, info, _, _ = ident(w, 1, 2)
    assert info.uncertainty is None


def test_the_simulation_band_is_the_models_response_and_tends_to_the_gains() -> None:
    w, _, _ = second_order_data(11)
    sysh, info, _, _ = ident(w, 1, 2, uncertainty=True)
    bars = info.uncertainty
    u = np.random.default_rng(12).standard_normal((60, 1))
    x0 = np.array([0.3, -0.2])
    y, spread = bars.simulation(u, x0)
    expected = control.forced_response(sysh, U=u.T, X0=x0).outputs
    assert np.allclose(y[:, 0], expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())
    assert spread.shape == (60, 1) and np.all(spread[1:] > 0)
    step_response, step_spread = bars.simulation(np.ones((400, 1)))  # from rest: y -> G(1), its std -> std(G(1))
    assert np.isclose(step_response[-1, 0], bars.value("gain")[0, 0], rtol=1e-8)
    assert np.isclose(step_spread[-1, 0], bars.std("gain")[0, 0], rtol=1e-4)
    with pytest.raises(ValueError, match=r"u must be a finite \(T, m\) array with m = 1 columns"):
        bars.simulation(np.ones((10, 2)))
    with pytest.raises(ValueError, match="x0 must be a finite vector of the model's 2 states"):
        bars.simulation(u, np.zeros(3))
