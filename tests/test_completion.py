"""ident.completion and ident.data_driven: complete, forecast, the k-step predictor of compare, the
data-driven completion and the input prior (29-completion-and-forecasting.md)."""
from __future__ import annotations

import warnings

import control
import matplotlib
import numpy as np
import pytest

from conftest import warnings_as_errors
from ident import InputPrior, StatePrior, UnstableModelWarning, compare, complete, forecast, misfit
from ident.completion import k_step_outputs
from ident.data_driven import reference_structure
from ident.representations import simulate

matplotlib.use("Agg")


def stable_system(seed: int, n: int = 4, m: int = 2, p: int = 1, radius: float = 0.9):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A *= radius / np.abs(np.linalg.eigvals(A)).max()
    return control.ss(A, rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m)), 1)


def trajectory(system, n_samples: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n_samples, system.ninputs))
    return np.hstack([u, simulate(system, u, rng.standard_normal(system.nstates))])


def determined_gaps(n_samples: int, seed: int) -> np.ndarray:
    """Gaps the observed values determine (m = 2, p = 1): outputs, and one input where the output is seen."""
    rng = np.random.default_rng(seed)
    gaps = np.zeros((n_samples, 3), bool)
    gaps[:, 2] = rng.random(n_samples) < 0.3
    gaps[:, 0] = ~gaps[:, 2] & (rng.random(n_samples) < 0.3)
    gaps[-3:] = False  # the last samples seen: nothing after them fixes a missing input there
    return gaps


SYSTEM = stable_system(1)
W_EXACT = trajectory(SYSTEM, 80, 2)
GAPS = determined_gaps(80, 3)


def relative_error(estimate, truth) -> float:
    return float(np.linalg.norm(estimate - truth) / np.linalg.norm(truth))


def test_exact_data_are_completed_exactly_with_the_model_and_from_a_reference():
    gappy = np.where(GAPS, np.nan, W_EXACT)
    by_model = complete(gappy, SYSTEM)
    by_data = complete(gappy, w_ref=trajectory(SYSTEM, 400, 4))
    assert relative_error(by_model.w[GAPS], W_EXACT[GAPS]) < 1e-8
    assert relative_error(by_data.w[GAPS], W_EXACT[GAPS]) < 1e-8
    assert by_model.method == "model" and by_data.method == "data-driven"
    assert np.array_equal(by_model.w[~GAPS], W_EXACT[~GAPS])  # the observed values as given
    assert np.array_equal(by_model.missing, GAPS)
    assert by_model.misfit < 1e-16 * np.sum(W_EXACT ** 2) * 1e4


def test_complete_fills_the_gaps_with_misfits_trajectory_on_noisy_data():
    rng = np.random.default_rng(5)
    noisy = W_EXACT + 0.1 * rng.standard_normal(W_EXACT.shape)
    gappy = np.where(rng.random(noisy.shape) < 0.2, np.nan, noisy)
    before = gappy.copy()
    completion = complete(gappy, SYSTEM)
    M, wh, _ = misfit(gappy, SYSTEM)
    missing = np.isnan(gappy)
    assert np.array_equal(gappy, before, equal_nan=True)  # the caller's array is not touched
    assert np.allclose(completion.w[missing], wh[missing], rtol=0, atol=1e-12 * np.abs(wh).max())
    assert np.allclose(completion.wh, wh, rtol=0, atol=1e-12 * np.abs(wh).max())
    assert completion.misfit == pytest.approx(M, rel=1e-10)


def test_forecast_equals_the_completion_with_the_future_outputs_missing():
    rng = np.random.default_rng(6)
    past = W_EXACT[:50] + 0.05 * rng.standard_normal((50, 3))
    u_future = W_EXACT[50:, :2]
    ahead = forecast(SYSTEM, past, u_future)
    joined = np.vstack([past, np.hstack([u_future, np.full((30, 1), np.nan)])])
    completion = complete(joined, SYSTEM)
    assert ahead.y.shape == (30, 1) and ahead.n_past == 50
    assert np.abs(ahead.y - completion.w[50:, 2:]).max() <= 1e-10 * np.abs(ahead.y).max()
    assert np.array_equal(ahead.w[50:, :2], u_future)
    exact = forecast(SYSTEM, W_EXACT[:50], u_future)  # exact past: the true future outputs
    assert relative_error(exact.y, W_EXACT[50:, 2:]) < 1e-8


def test_data_driven_forecast_agrees_with_the_model_on_exact_data():
    reference = trajectory(SYSTEM, 400, 7)
    structure = reference_structure(reference)
    assert (structure.m, structure.ell, structure.n) == (2, 4, 4)  # one output: the lag is the order
    chain = control.ss(np.diag(np.ones(3), -1), np.eye(4)[:, :1], np.eye(4)[[3, 1]], np.zeros((2, 1)), 1)
    assert (reference_structure(trajectory(chain, 200, 8)).ell, reference_structure(trajectory(chain, 200, 8)).n) == (2, 4)
    with pytest.raises(ValueError, match="fewer than the lag 4 of the reference trajectory"):
        forecast(None, W_EXACT[:3], W_EXACT[3:10, :2], w_ref=reference)
    by_data = forecast(None, W_EXACT[:20], W_EXACT[20:40, :2], w_ref=reference)
    by_model = forecast(SYSTEM, W_EXACT[:20], W_EXACT[20:40, :2])
    assert relative_error(by_data.y, by_model.y) < 1e-8
    assert by_data.method == "data-driven"


def test_data_frames_come_back_as_data_frames():
    pandas = pytest.importorskip("pandas")
    named = control.ss(SYSTEM.A, SYSTEM.B, SYSTEM.C, SYSTEM.D, 1, inputs=["a", "b"], outputs=["y"])
    frame = pandas.DataFrame(np.where(GAPS, np.nan, W_EXACT)[:, [2, 0, 1]], columns=["y", "a", "b"])
    completion = complete(frame, named)
    assert list(completion.w.columns) == ["y", "a", "b"] and completion.w.index.equals(frame.index)
    assert relative_error(completion.w.to_numpy()[GAPS[:, [2, 0, 1]]], W_EXACT[:, [2, 0, 1]][GAPS[:, [2, 0, 1]]]) < 1e-8
    past = pandas.DataFrame(W_EXACT[:50], columns=["a", "b", "y"])
    future = pandas.DataFrame(W_EXACT[50:, :2], columns=["a", "b"], index=range(50, 80))
    ahead = forecast(named, past, future)
    assert list(ahead.y.columns) == ["y"] and list(ahead.y.index) == list(range(50, 80))
    assert relative_error(ahead.y.to_numpy(), W_EXACT[50:, 2:]) < 1e-8


def test_weights_weigh_the_misfit():
    rng = np.random.default_rng(8)
    noisy = np.where(GAPS, np.nan, W_EXACT + 0.1 * rng.standard_normal(W_EXACT.shape))
    plain = complete(noisy, SYSTEM)
    doubled = complete(noisy, SYSTEM, weights=[2.0, 2.0, 2.0])  # the same weight everywhere: the same trajectory
    assert np.allclose(doubled.wh, plain.wh, rtol=0, atol=1e-10 * np.abs(plain.wh).max())
    assert doubled.misfit == pytest.approx(2 * plain.misfit, rel=1e-10)
    heavy = complete(noisy, SYSTEM, weights=[1.0, 1.0, 1e6])  # the outputs almost exact
    exact_outputs = complete(noisy, SYSTEM, exct=[2])
    scale = np.abs(exact_outputs.wh).max()
    assert np.abs(heavy.wh - exact_outputs.wh).max() < 1e-3 * scale
    assert np.abs(plain.wh - exact_outputs.wh).max() > 1e-2 * scale  # the weight changed something


def test_the_input_prior_pulls_the_missing_inputs_to_its_mean():
    gappy = W_EXACT.copy()
    gappy[-1, :2] = np.nan  # both inputs at the last sample: y(T) = C x + D u fixes only one direction
    mean = np.array([0.3, -0.2])
    tight = complete(gappy, SYSTEM, input_prior=InputPrior(mean, np.array([1e-7, 1e-7]), 0.1))
    assert np.abs(tight.w[-1, :2] - mean).max() < 1e-5
    plain = complete(gappy, SYSTEM)
    D = np.asarray(SYSTEM.D)[0]
    free = np.array([D[1], -D[0]]) / np.linalg.norm(D)  # the direction the data leave free: least norm without a prior
    assert abs(free @ plain.w[-1, :2]) < 1e-8 * np.abs(W_EXACT).max()
    assert np.array_equal(tight.w[:-1], W_EXACT[:-1])  # the observed values as given
    wide = InputPrior(np.zeros(2), np.array([1e6, 1e6]), 0.1)
    noisy_gaps = np.where(GAPS, np.nan, W_EXACT + 0.1 * np.random.default_rng(9).standard_normal(W_EXACT.shape))
    assert np.abs(complete(noisy_gaps, SYSTEM, input_prior=wide).w - complete(noisy_gaps, SYSTEM).w).max() < 1e-6


def test_input_prior_from_data():
    prior = InputPrior.from_data(W_EXACT, 2, misfit=0.8 * W_EXACT.size)
    assert np.allclose(prior.mean, W_EXACT[:, :2].mean(axis=0)) and np.allclose(prior.std, W_EXACT[:, :2].std(axis=0))
    assert prior.noise == pytest.approx(np.sqrt(0.8), rel=1e-12)


@pytest.mark.parametrize("horizon", [1, 3, 10, 79, 80, 500])
def test_every_horizon_predicts_exact_data_exactly(horizon):
    comparison = compare(W_EXACT, SYSTEM, horizon=horizon)
    assert np.all(np.abs(comparison.fit - 100) < 1e-8)


def test_a_horizon_beyond_the_record_is_the_simulation():
    rng = np.random.default_rng(10)
    noisy = W_EXACT + 0.2 * rng.standard_normal(W_EXACT.shape)
    simulation = compare(noisy, SYSTEM)
    for horizon in (len(noisy), 10 * len(noisy)):
        assert np.all(np.abs(compare(noisy, SYSTEM, horizon=horizon).fit - simulation.fit) < 1e-10)
    short = compare(noisy, SYSTEM, horizon=1)
    assert not np.allclose(short.fit, simulation.fit, rtol=0, atol=1e-3)  # a short horizon is another number
    assert short.horizon == 1 and simulation.horizon is None
    labels = [line.get_label() for line in short.plot().axes[0].get_lines()]
    assert labels == ["measured", "1-step predicted"]
    assert np.allclose(short.series_fits[0], short.fit, rtol=0, atol=1e-9)  # one series: its fit is the fit


def test_a_k_step_prediction_is_the_completion_of_its_window():
    rng = np.random.default_rng(11)
    noisy = W_EXACT + 0.2 * rng.standard_normal(W_EXACT.shape)
    k, past = 5, 6
    simulated = np.zeros((80, 1))
    predicted = k_step_outputs(SYSTEM, noisy, k, simulated, past)
    for t in (k + past - 1, 40, 79):
        start = t - k + 1
        window = np.vstack([noisy[start - past:start], np.hstack([noisy[start:t + 1, :2], np.full((k, 1), np.nan)])])
        by_completion = complete(window, SYSTEM).w[-1, 2]
        assert predicted[t, 0] == pytest.approx(by_completion, abs=1e-9 * np.abs(noisy).max())
    assert np.array_equal(predicted[:k + past - 1], simulated[:k + past - 1])  # no full past: the simulation's


def test_forecast_warns_of_an_unstable_model_with_a_long_horizon():
    unstable = stable_system(12, radius=1.05)
    past = trajectory(unstable, 20, 13)
    with pytest.warns(UnstableModelWarning, match="spectral radius 1.05"):
        forecast(unstable, past, np.zeros((100, 2)))
    with warnings_as_errors(UnstableModelWarning):
        forecast(unstable, past, np.zeros((3, 2)))  # 1.05^3 < 10: no warning


def test_plots_draw_data_and_gaps():
    completion = complete(np.where(GAPS, np.nan, W_EXACT), SYSTEM)
    figure = completion.plot(title="completed")
    assert len(figure.axes) == 3
    assert any(line.get_label() == "filled gaps" for line in figure.axes[2].get_lines())
    ahead = forecast(SYSTEM, W_EXACT[:50], W_EXACT[50:, :2])
    assert len(ahead.plot().axes) == 3


# ---- the state prior of forecast (a short noisy past; issue 33's robot arm) ----
RESONANT = control.ss([[2 * np.sqrt(0.95) * np.cos(0.3), -0.95], [1.0, 0.0]], [[1.0], [0.0]], [[0.3, 0.1]], [[0.0]],
                      1)  # poles 0.975 exp(+-0.3 i): lightly damped


def test_the_state_prior_of_exact_data_has_no_weight():
    prior = StatePrior.from_data(W_EXACT, SYSTEM)
    assert prior.noise < 1e-10 * np.abs(W_EXACT).max()
    assert prior.mean.shape == (4,) and prior.cov.shape == (4, 4) and np.all(np.linalg.eigvalsh(prior.cov) > 0)
    with_prior = forecast(SYSTEM, W_EXACT[:20], W_EXACT[20:, :2], state_prior=prior)
    assert relative_error(with_prior.y, W_EXACT[20:, 2:]) < 1e-8  # the true samples
    assert relative_error(with_prior.y, forecast(SYSTEM, W_EXACT[:20], W_EXACT[20:, :2]).y) < 1e-8
    assert relative_error(with_prior.w[:20], W_EXACT[:20]) < 1e-8  # the past is not corrected
    assert with_prior.method == "model with a state prior" and with_prior.misfit < 1e-16 * np.sum(W_EXACT ** 2) * 1e4


def test_the_state_prior_states_are_the_models_states():
    w = trajectory(RESONANT, 300, 11)
    prior = StatePrior.from_data(w, RESONANT)
    A, B = np.asarray(RESONANT.A), np.asarray(RESONANT.B)
    rng = np.random.default_rng(11)  # trajectory()'s draws: the input, then the initial state
    rng.standard_normal((300, 1))
    state, states = rng.standard_normal(2), []
    for u in w[:, 0]:
        states.append(state)
        state = A @ state + B[:, 0] * u
    states = np.array(states + [state])[2:]  # x(past) .. x(T) with past = the lag 2
    assert np.allclose(prior.mean, states.mean(axis=0), rtol=0, atol=1e-8 * np.abs(states).max())
    assert np.allclose(prior.cov, np.cov(states.T, bias=True), rtol=0, atol=1e-8 * np.abs(states).max() ** 2)


def test_a_state_prior_of_large_noise_forecasts_from_its_mean():
    w = trajectory(RESONANT, 60, 12)
    mean = np.array([0.5, -0.25])
    loud = StatePrior(mean, np.eye(2), 1e8)
    ahead = forecast(RESONANT, w[:2], w[2:, :1], exct=[0], state_prior=loud)
    A, B = np.asarray(RESONANT.A), np.asarray(RESONANT.B)
    end = A @ (A @ mean + B[:, 0] * w[0, 0]) + B[:, 0] * w[1, 0]  # the mean carried through the exact past inputs
    assert relative_error(ahead.y, simulate(RESONANT, w[2:, :1], end)) < 1e-8
    assert np.array_equal(ahead.w[:2, 0], w[:2, 0])  # exact inputs are kept


def test_a_state_prior_makes_a_short_noisy_past_forecast_better():
    """A lightly damped model, a past of its lag (2 samples) with errors of 0.3 times the output's spread:
    the state from the misfit alone takes the errors in full, the prior weighs them against what the
    identification data say. Over 40 draws the mean squared forecast error (what the most probable
    state lowers) with the prior is less than half the one without (0.14 of it when written)."""
    rng = np.random.default_rng(14)
    identification = trajectory(RESONANT, 500, 15)
    size = 0.3 * identification.std(axis=0)
    noisy = identification + np.hstack([np.zeros((500, 1)), size[1] * rng.standard_normal((500, 1))])  # exact input
    prior = StatePrior.from_data(noisy, RESONANT, exct=[0])
    assert prior.noise == pytest.approx(size[1], rel=0.2)  # the misfit per corrected value: the errors' size
    without, with_prior = [], []
    for draw in range(40):
        w = trajectory(RESONANT, 42, 100 + draw)
        past = w[:2] + np.hstack([np.zeros((2, 1)), size[1] * rng.standard_normal((2, 1))])
        truth = w[2:, 1:]
        without.append(np.sum((forecast(RESONANT, past, w[2:, :1], exct=[0]).y - truth) ** 2))
        with_prior.append(np.sum((forecast(RESONANT, past, w[2:, :1], exct=[0], state_prior=prior).y - truth) ** 2))
    assert np.mean(with_prior) < 0.5 * np.mean(without)
