"""ident(..., offset=True): affine models (w - c a trajectory of the linear model), the Offset record,
and the offset= of misfit, compare and resid (issue 31)."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from ident import Offset, compare, ident, misfit, resid
from ident.identification import UnstableModelWarning
from ident.representations import markov_parameters, random_system, simulate
from literate_tools.tangled import examples


def affine_data(m: int, p: int, ell: int, lengths, seed: int, offset_size: float = 5.0):
    """(plant, offset, series): trajectories of a random plant started in a transient, plus a constant offset."""
    rng = np.random.default_rng(seed)
    plant = random_system(m, p, ell, rng)
    offset = offset_size * (1 + rng.random(m + p)) * rng.choice([-1, 1], m + p)
    series = []
    for length in lengths:
        u = rng.standard_normal((length, m))
        series.append(np.hstack([u, simulate(plant, u, 5 * rng.standard_normal(plant.nstates))]) + offset)
    return plant, offset, series


def static_gain(sys) -> np.ndarray:
    return sys.D + sys.C @ np.linalg.solve(np.eye(sys.nstates) - sys.A, sys.B)


def relative_error(estimate, truth) -> float:
    return float(np.linalg.norm(np.asarray(estimate) - truth) / np.linalg.norm(truth))


def offset_error(found: Offset, plant, true_offset: np.ndarray) -> float:
    """How far found.outputs is from the plant's steady state for found.inputs (offsets are a class)."""
    m = plant.ninputs
    expected = true_offset[m:] + static_gain(plant) @ (found.inputs - true_offset[:m])
    return relative_error(found.outputs, expected)


@pytest.mark.parametrize("m, p, ell, lengths", [(1, 1, 2, [120]), (2, 2, 2, [100]), (1, 2, 3, [90, 140, 60])])
def test_exact_affine_data_give_the_model_and_the_offset(m, p, ell, lengths) -> None:
    plant, true_offset, series = affine_data(m, p, ell, lengths, seed=m + 10 * p + ell)
    w = series if len(series) > 1 else series[0]
    model, info, wh, xini = ident(w, m, ell, offset=True)
    assert relative_error(markov_parameters(model, 12), markov_parameters(plant, 12)) <= 1e-10
    assert offset_error(info.offset, plant, true_offset) <= 1e-10
    inputs = np.vstack(series)[:, :m]
    assert np.allclose(info.offset.inputs, inputs.mean(axis=0), rtol=1e-13, atol=0)
    # wh - c is the trajectory of the model from xini
    for k, (w_k, wh_k) in enumerate(zip(series, wh if len(series) > 1 else [wh])):
        assert np.max(np.abs(wh_k - w_k)) <= 1e-9 * np.max(np.abs(w_k))
        shifted = wh_k - info.offset.vector
        simulated = simulate(model, shifted[:, :m], xini[:, k])
        assert np.max(np.abs(simulated - shifted[:, m:])) <= 1e-8 * np.max(np.abs(shifted))
    centred = [w_k - np.vstack(series).mean(axis=0) for w_k in series]
    model_c, _, _, _ = ident(centred if len(series) > 1 else centred[0], m, ell)
    assert relative_error(markov_parameters(model_c, 12), markov_parameters(plant, 12)) >= 1e-3


@pytest.mark.parametrize("init", ["lra", "arx", "subspace"])
def test_each_start_reaches_the_exact_affine_model(init) -> None:
    plant, true_offset, (w,) = affine_data(1, 2, 2, [300], seed=7)
    model, info, _, _ = ident(w, 1, 2, offset=True, init=init, refine=1e-12)  # each start to its minimum
    assert info.start == init
    assert relative_error(markov_parameters(model, 12), markov_parameters(plant, 12)) <= 1e-9
    assert offset_error(info.offset, plant, true_offset) <= 1e-9


def test_a_given_sys0_starts_the_affine_problem() -> None:
    plant, true_offset, (w,) = affine_data(1, 1, 2, [200], seed=8)
    model, info, _, _ = ident(w, 1, 2, offset=True, sys0=plant)
    assert info.start == "sys0" and info.M <= 1e-18 * np.sum(w ** 2)
    assert offset_error(info.offset, plant, true_offset) <= 1e-10


@pytest.mark.parametrize("mode", ["eiv", "oe"])
def test_noisy_affine_data_several_series(mode) -> None:
    plant, true_offset, series = affine_data(1, 2, 2, [150, 250], seed=21)
    rng = np.random.default_rng(22)
    noisy = [w + 0.05 * rng.standard_normal(w.shape) * ([0, 1, 1] if mode == "oe" else 1) for w in series]
    exct = [0] if mode == "oe" else None
    model, info, wh, xini = ident(noisy, 1, 2, offset=True, exct=exct)
    # the misfit of the model with its offset is info.M, and the affine class holds the truth
    M, wh_again, xini_again = misfit(noisy, model, exct=exct, offset=info.offset)
    assert M == pytest.approx(info.M, rel=1e-7)
    assert all(np.allclose(a, b, rtol=0, atol=1e-7 * np.max(np.abs(a))) for a, b in zip(wh, wh_again))
    M_true, _, _ = misfit(noisy, plant, exct=exct, offset=Offset(true_offset[:1], true_offset[1:]))
    assert info.M <= M_true
    if mode == "oe":
        assert all(np.array_equal(a[:, 0], b[:, 0]) for a, b in zip(wh, noisy))
    # without the offset the linear model misses the data by far more
    assert misfit(noisy, model, exct=exct)[0] > 100 * info.M
    assert relative_error(markov_parameters(model, 12), markov_parameters(plant, 12)) <= 0.2


def test_compare_and_resid_apply_the_offset() -> None:
    plant, true_offset, (w,) = affine_data(1, 2, 2, [400], seed=31)
    w = w + 0.02 * np.random.default_rng(32).standard_normal(w.shape)
    model, info, _, _ = ident(w[:300], 1, 2, offset=True)
    with_offset = compare(w[300:], model, offset=info.offset)
    by_hand = compare(w[300:] - info.offset.vector, model)
    assert np.allclose(with_offset.fit, by_hand.fit, rtol=1e-10, atol=1e-10) and np.all(with_offset.fit > 90)
    assert np.allclose(with_offset.y[0], w[300:, 1:], rtol=0, atol=1e-12 * np.max(np.abs(w)))
    assert np.allclose(with_offset.yh[0], by_hand.yh[0] + info.offset.outputs, rtol=1e-10, atol=1e-10)
    assert np.all(compare(w[300:], model).fit < with_offset.fit - 50)  # without it, the offset scores as error
    r_offset, r_hand = resid(w[300:], model, offset=info.offset), resid(w[300:] - info.offset.vector, model)
    assert np.allclose(r_offset.autocorrelation, r_hand.autocorrelation, rtol=1e-9, atol=1e-12)
    assert np.allclose(r_offset.residuals[0], r_hand.residuals[0], rtol=1e-9, atol=1e-12)


def test_a_reduced_affine_model_keeps_its_offset_and_misfit() -> None:
    plant, true_offset, (w,) = affine_data(1, 2, 2, [300], seed=41)
    w = w + 0.05 * np.random.default_rng(42).standard_normal(w.shape)
    model, info, _, _ = ident(w, 1, 2, offset=True, n=3)
    assert model.nstates == 3 and info.reduction is not None and info.offset is not None
    assert misfit(w, model, offset=info.offset)[0] == pytest.approx(info.M, rel=1e-9)


def test_the_offset_scales_with_the_data_exactly() -> None:
    _, _, (w,) = affine_data(1, 1, 2, [150], seed=51)
    w = w + 0.05 * np.random.default_rng(52).standard_normal(w.shape)
    _, info, _, _ = ident(w, 1, 2, offset=True)
    _, info_scaled, _, _ = ident(2.0 ** 40 * w, 1, 2, offset=True)
    assert np.allclose(info_scaled.offset.vector, 2.0 ** 40 * info.offset.vector, rtol=1e-9, atol=0)


def test_the_default_takes_the_data_as_given() -> None:
    _, _, (w,) = affine_data(1, 1, 2, [150], seed=61)
    _, info, _, _ = ident(w - w.mean(axis=0), 1, 2)
    assert info.offset is None


def test_misfit_with_an_offset_and_initial_samples() -> None:
    plant, true_offset, (w,) = affine_data(1, 1, 2, [100], seed=71)
    offset = Offset(true_offset[:1], true_offset[1:])
    M, wh, _ = misfit(w[2:], plant, wini=[w[:2]], offset=offset)  # the two samples before, in the data's units
    assert M <= 1e-20 * np.sum(w ** 2) and np.allclose(wh, w[2:], rtol=0, atol=1e-9 * np.max(np.abs(w)))
    M_rest, _, _ = misfit(w[2:], plant, wini=0, offset=offset)  # rest at the offset: not these data
    assert M_rest > 1e-3


def test_raw_data_far_from_zero_mean_warn_what_to_do() -> None:
    path = examples.shared_path("daisy", "dryer.dat")
    if not path:
        pytest.skip("DAISY's dryer.dat not found")
    w = np.loadtxt(path)[:700]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ident(w, 1, 5)
    messages = [str(c.message) for c in caught if issubclass(c.category, UnstableModelWarning)]
    assert any("the data's means are far from zero" in text and "pass offset=True or centre the data" in text
               for text in messages), messages
    for data, affine in ((w - w.mean(axis=0), False), (w, True)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            ident(data, 1, 5, offset=affine)
        assert not any("far from zero" in str(c.message) for c in caught)


def test_offset_record() -> None:
    offset = Offset([1, 2], np.array([3.0]))
    assert offset.inputs.dtype == float and offset.vector.tolist() == [1.0, 2.0, 3.0]
    with pytest.raises(ValueError, match="read-only"):
        offset.inputs[0] = 5.0


def test_the_lag_sweep_and_choice_take_the_offset_and_validate_with_each_lags_own() -> None:
    from ident import choose_lag, misfit_vs_lag
    plant, true_offset, (w,) = affine_data(1, 2, 2, [400], seed=31)
    w = w + 0.02 * np.random.default_rng(32).standard_normal(w.shape)
    affine = misfit_vs_lag(w[:300], 1, [1, 2], validation=w[300:], offset=True)
    for k, lag in enumerate([1, 2]):  # each lag's fit is compare's with that lag's own offset
        model, info, _, _ = ident(w[:300], 1, lag, offset=True)
        assert affine.misfit[k] == pytest.approx(info.M, rel=1e-6)
        assert affine.fit[k] == pytest.approx(np.mean(compare(w[300:], model, offset=info.offset).fit), abs=1e-6)
    assert affine.fit[1] > 90
    choice = choose_lag(w, 1, [1, 2, 3], offset=True)
    assert choice.ell == 2 and np.all(np.isfinite(choice.holdout_fits))
    with pytest.raises(TypeError, match="offset must be True or False"):
        misfit_vs_lag(w, 1, [1], offset="yes")


def test_the_command_lines_lag_takes_the_offset(tmp_path, capsys) -> None:
    from ident import cli
    plant, true_offset, (w,) = affine_data(1, 1, 1, [300], seed=5)
    data = tmp_path / "data.csv"
    np.savetxt(data, w + 0.01 * np.random.default_rng(6).standard_normal(w.shape), delimiter=",", header="u,y",
               comments="")
    common = ["lag", str(data), "--inputs", "u", "--outputs", "y", "--lags", "1,2", "--modes", "oe", "--plot",
              str(tmp_path / "lag.png")]
    assert cli.main([*common, "--offset", "fit"]) == 0
    fit_output = capsys.readouterr().out
    assert "chosen lag (OE" in fit_output
    assert cli.main([*common, "--no-center", "--offset", "fit"]) == 2
    assert "--no-center is --offset none" in capsys.readouterr().err
