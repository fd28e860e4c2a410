"""The engineer's workflow (issue 17): the sample time, pandas DataFrames with names, a chosen order,
compare and resid, the model file read back, the command line's --version and column names."""
from __future__ import annotations

import json
import warnings

import control
import numpy as np
import pandas as pd
import pytest

from conftest import warnings_as_errors
from ident import compare, fit_percent, ident, load_model, misfit, resid, validate
from ident.cli import main
from ident.reduction import balanced_truncation
from ident.representations import inistate, make_ss, random_system, simulate


def noisy_data(m=1, p=1, ell=2, T=300, noise=0.05, seed=0):
    rng = np.random.default_rng(seed)
    system = random_system(m, p, ell, rng)
    u = rng.standard_normal((T, m))
    y = simulate(system, u, rng.standard_normal(ell * p))
    w0 = np.hstack([u, y])
    return system, w0 + noise * rng.standard_normal(w0.shape)


# -- the sample time ---------------------------------------------------------------------------------

def test_the_model_has_the_sample_time_asked_for_and_simulates_on_the_users_time_axis() -> None:
    _, w = noisy_data()
    sysh, info, _, _ = ident(w, 1, 2, dt=0.1)
    assert sysh.dt == 0.1
    t = 0.1 * np.arange(len(w))
    response = control.forced_response(sysh, T=t, U=w[:, 0])  # raised with dt = 1
    assert response.outputs.shape == (len(w),)
    assert ident(w, 1, 2)[0].dt == 1


def test_the_sample_time_of_sys0_is_inherited_and_a_contradiction_refused() -> None:
    system, w = noisy_data()
    sys0 = make_ss(system.A, system.B, system.C, system.D, 0.25)
    assert ident(w, 1, 2, sys0=sys0)[0].dt == 0.25
    assert ident(w, 1, 2, sys0=sys0, dt=0.25)[0].dt == 0.25
    with pytest.raises(ValueError, match=r"dt = 0.1 but sys0 has dt = 0.25"):
        ident(w, 1, 2, sys0=sys0, dt=0.1)
    unspecified = make_ss(system.A, system.B, system.C, system.D, True)
    assert ident(w, 1, 2, sys0=unspecified)[0].dt == 1


@pytest.mark.parametrize("dt, error", [(0, ValueError), (-0.1, ValueError), (np.nan, ValueError),
                                       (np.inf, ValueError), ("0.1", TypeError), (True, TypeError),
                                       ([0.1], TypeError)])
def test_a_bad_sample_time_is_refused_by_name(dt, error) -> None:
    _, w = noisy_data(T=60)
    with pytest.raises(error, match=r"^dt must be"):
        ident(w, 1, 2, dt=dt)


def test_misfit_and_the_validation_functions_take_models_of_any_sample_time() -> None:
    _, w = noisy_data()
    model_1, _, _, _ = ident(w, 1, 2)
    model_dt = make_ss(model_1.A, model_1.B, model_1.C, model_1.D, 0.01)
    scale = float(np.sum(w ** 2))
    assert abs(misfit(w, model_dt)[0] - misfit(w, model_1)[0]) <= 1e-10 * scale
    for model in (model_1, model_dt):
        fits = validate(model, w[:, :1], w[:, 1:]).fit
        assert fits[0] > 80
    assert np.allclose(compare(w, model_dt).fit, compare(w, model_1).fit, atol=1e-8)
    assert np.allclose(resid(w, model_dt).autocorrelation, resid(w, model_1).autocorrelation, atol=1e-8)
    x0 = inistate(w, model_dt)
    assert np.all(np.isfinite(simulate(model_dt, w[:, :1], x0)))


# -- pandas ------------------------------------------------------------------------------------------

def frame_of(w, columns=("force", "position"), start=10):
    return pd.DataFrame(w, columns=list(columns), index=pd.RangeIndex(start, start + len(w), name="sample"))


def test_a_data_frame_names_the_model_and_comes_back_as_a_data_frame() -> None:
    _, w = noisy_data()
    frame = frame_of(w)
    sysh, info, wh, xini = ident(frame, 1, 2, dt=0.1)
    assert sysh.input_labels == ["force"] and sysh.output_labels == ["position"]
    assert isinstance(wh, pd.DataFrame)
    assert wh.index.equals(frame.index) and wh.columns.equals(frame.columns)
    _, info_array, wh_array, _ = ident(w, 1, 2)
    assert abs(info.M - info_array.M) <= 1e-8 * info_array.M
    assert np.allclose(wh.to_numpy(), wh_array, atol=1e-8 * np.abs(w).max())
    assert frame.to_numpy().base is not wh.to_numpy().base  # the caller's data are not aliased


def test_exct_may_name_columns() -> None:
    _, w = noisy_data(m=2, p=1)
    frame = frame_of(w, ("force", "torque", "position"))
    _, info_names, wh, _ = ident(frame, 2, 2, exct=["torque", "force"])
    _, info_indices, _, _ = ident(w, 2, 2, exct=[0, 1])
    assert abs(info_names.M - info_indices.M) <= 1e-8 * info_indices.M
    assert np.array_equal(wh[["force", "torque"]].to_numpy(), frame[["force", "torque"]].to_numpy())
    _, info_one, _, _ = ident(frame, 2, 2, exct="force")
    _, info_mixed, _, _ = ident(frame, 2, 2, exct=["force", 1])  # an integer that is no name: a position
    assert abs(info_mixed.M - info_indices.M) <= 1e-8 * info_indices.M and info_one.M <= info_indices.M


def test_integer_column_names_are_names_first() -> None:
    _, w = noisy_data(m=2, p=1)
    frame = pd.DataFrame(w, columns=[2, 0, 1])  # the column named 0 is the second
    _, info_named, wh, _ = ident(frame, 2, 2, exct=[0])
    assert np.array_equal(wh[0].to_numpy(), frame[0].to_numpy())
    assert not np.array_equal(wh[2].to_numpy(), frame[2].to_numpy())


def test_a_sequence_of_data_frames_is_several_series() -> None:
    _, w = noisy_data(T=400)
    frames = [frame_of(w[:250]), frame_of(w[250:], start=0)]
    sysh, info, wh, xini = ident(frames, 1, 2)
    _, info_arrays, _, _ = ident([w[:250], w[250:]], 1, 2)
    assert isinstance(wh, list) and all(isinstance(x, pd.DataFrame) for x in wh)
    assert wh[1].index.equals(frames[1].index) and xini.shape == (2, 2)
    assert abs(info.M - info_arrays.M) <= 1e-8 * info_arrays.M


def test_misfit_compare_and_resid_take_data_frames() -> None:
    system, w = noisy_data()
    frame = frame_of(w)
    M, wh, _ = misfit(frame, system)
    assert isinstance(wh, pd.DataFrame) and wh.index.equals(frame.index)
    assert abs(M - misfit(w, system)[0]) <= 1e-10 * float(np.sum(w ** 2))
    assert np.allclose(compare(frame, system).fit, compare(w, system).fit)
    assert resid(frame, system).autocorrelation.shape == (26, 1)


def with_missing(frame):
    frame.loc[15, "position"] = pd.NA  # pandas' missing value in a nullable column
    return frame


@pytest.mark.parametrize("data, error, words", [
    (lambda w: pd.DataFrame({"force": w[:, 0], "note": ["x"] * len(w)}), TypeError,
     r"w has non-numeric column\(s\) 'note'"),
    (lambda w: pd.DataFrame({"force": w[:, 0], "when": pd.date_range("2024", periods=len(w), freq="s")}),
     TypeError, r"w has non-numeric column\(s\) 'when'"),
    (lambda w: pd.DataFrame({"force": w[:, 0], "position": w[:, 1].astype(complex)}), TypeError,
     r"non-numeric column\(s\) 'position' \(complex128\)"),
    (lambda w: pd.DataFrame(w, columns=["a", "a"]), ValueError, r"w has the column name\(s\) 'a' more than once"),
    (lambda w: [frame_of(w), frame_of(w, ("position", "speed"))], ValueError,
     r"w\[1\] has the columns \['position', 'speed'\] but w\[0\] has \['force', 'position'\]: w\[1\] lacks "
     r"'force'; w\[1\] has 'speed', not expected"),
    (lambda w: [frame_of(w), w], TypeError, r"w\[1\] is a ndarray, but w holds DataFrames"),
])
def test_bad_data_frames_are_refused_by_name(data, error, words) -> None:
    _, w = noisy_data(T=60)
    with pytest.raises(error, match=words):
        ident(data(w), 1, 2)


def test_pandas_missing_values_are_missing_samples() -> None:
    """pd.NA in a nullable column is a missing sample, as NaN is (issue 29): taken, and refused only in an
    exact variable, by its name and first sample."""
    _, w = noisy_data(T=60)
    frame = with_missing(frame_of(w).astype({"position": "Float64"}))
    with_nan = np.where(np.arange(w.size).reshape(w.shape) == 5 * 2 + 1, np.nan, w)  # sample 5 (index 15), variable 1
    assert ident(frame, 1, 2)[1].M == pytest.approx(ident(with_nan, 1, 2)[1].M, rel=1e-9)
    with pytest.raises(ValueError, match=r"variable 'position' is exact \(exct\) but is missing .* at sample 5"):
        ident(frame, 1, 2, exct=["position"])


def test_exct_naming_a_column_that_does_not_exist_is_refused() -> None:
    _, w = noisy_data(T=60)
    with pytest.raises(ValueError, match=r"exct names 'speed', which is not a column of w \(its columns: 'force', "
                                         r"'position'\)"):
        ident(frame_of(w), 1, 2, exct=["speed"])
    with pytest.raises(TypeError, match=r"column names when w is a DataFrame"):
        ident(w, 1, 2, exct=["force"])


# -- DataFrames: names, not positions, and time indexes (issue 32) --------------------------------------

def test_misfit_compare_and_resid_take_a_frames_columns_by_name() -> None:
    system, w = noisy_data(m=1, p=2, T=300)
    named = make_ss(system.A, system.B, system.C, system.D, 1, inputs=["force"], outputs=["position", "angle"])
    frame = pd.DataFrame(w, columns=["force", "position", "angle"])
    shuffled = frame[["angle", "force", "position"]]  # the columns reordered: the same data
    M, wh, _ = misfit(frame, named)
    M_shuffled, wh_shuffled, _ = misfit(shuffled, named)
    assert abs(M_shuffled - M) <= 1e-10 * M  # by position: the outputs taken as inputs, a misfit far larger
    assert list(wh_shuffled.columns) == list(shuffled.columns)  # wh comes back in the caller's order
    assert np.allclose(wh_shuffled[list(frame.columns)].to_numpy(), wh.to_numpy(), atol=1e-10 * np.abs(w).max())
    assert np.allclose(compare(shuffled, named).fit, compare(frame, named).fit, atol=1e-8)
    assert compare(shuffled, named).fit.min() > 80
    assert np.allclose(resid(shuffled, named).autocorrelation, resid(frame, named).autocorrelation, atol=1e-8)
    M_exact, _, _ = misfit(shuffled, named, exct=["force"])  # exct names: the same variable in any order
    assert abs(M_exact - misfit(w, named, exct=[0])[0]) <= 1e-10 * M_exact
    u, y = frame[["force"]], frame[["angle", "position"]]
    assert np.allclose(validate(named, u, y).fit, validate(named, w[:, :1], w[:, 1:]).fit, atol=1e-8)  # model order
    assert np.allclose(fit_percent(frame[["position", "angle"]], frame[["angle", "position"]] * 0.9)[0],
                       fit_percent(w[:, 1:], 0.9 * w[:, 1:])[0], atol=1e-10)


def test_an_identified_model_meets_its_data_by_name() -> None:
    _, w = noisy_data(T=300)
    frame = frame_of(w)
    sysh, info, _, _ = ident(frame, 1, 2)
    reordered = frame[["position", "force"]]
    assert abs(misfit(reordered, sysh)[0] - info.M) <= 1e-8 * info.M
    _, info_sys0, _, _ = ident(reordered, 1, 2, sys0=sysh)  # a named sys0 orders the columns: force is the input
    assert abs(info_sys0.M - info.M) <= 1e-6 * info.M


def test_a_model_without_names_takes_a_frame_by_position_unless_the_columns_are_its_names() -> None:
    system, w = noisy_data()
    frame = frame_of(w)  # force, position: other names than u[0], y[0]
    assert abs(misfit(frame, system)[0] - misfit(w, system)[0]) <= 1e-10 * misfit(w, system)[0]
    by_default_names = pd.DataFrame(w[:, ::-1], columns=["y[0]", "u[0]"])
    assert abs(misfit(by_default_names, system)[0] - misfit(w, system)[0]) <= 1e-10 * misfit(w, system)[0]


def test_series_of_frames_are_matched_by_name() -> None:
    _, w = noisy_data(T=400)
    frames = [frame_of(w[:250]), frame_of(w[250:], start=0)]
    swapped = [frames[0], frames[1][["position", "force"]]]
    sysh, info, wh, _ = ident(frames, 1, 2)
    sysh_swapped, info_swapped, wh_swapped, _ = ident(swapped, 1, 2)
    assert abs(info_swapped.M - info.M) <= 1e-8 * info.M and sysh_swapped.input_labels == ["force"]
    assert list(wh_swapped[1].columns) == ["position", "force"]
    assert np.allclose(wh_swapped[1][["force", "position"]].to_numpy(), wh[1].to_numpy(), atol=1e-8 * np.abs(w).max())


@pytest.mark.parametrize("index, dt", [
    (pd.date_range("2024-01-01", periods=300, freq="100ms"), 0.1),
    (pd.timedelta_range(0, periods=300, freq="20ms"), 0.02),
    (pd.Index(0.1 * np.arange(300), name="time (s)"), 0.1),
    (pd.period_range("2024-01-01", periods=300, freq="2s"), 2.0),
    (pd.period_range("2024-01-01", periods=300, freq="D"), 86400.0),
    (pd.RangeIndex(5, 305), 1),  # sample numbers: no time, the default dt
    (pd.Index([f"sample {k}" for k in range(300)]), 1),  # labels: not read
])
def test_a_time_index_gives_the_sample_time(index, dt) -> None:
    _, w = noisy_data(T=300)
    frame = frame_of(w).set_axis(index)
    sysh, _, wh, _ = ident(frame, 1, 2)
    assert abs(sysh.dt - dt) <= 1e-12 * dt and wh.index.equals(frame.index)
    assert abs(ident(frame, 1, 2, dt=dt)[0].dt - dt) <= 1e-12 * dt  # the spacing asked for is no contradiction
    assert misfit(frame, sysh)[0] > 0 and compare(frame, sysh).fit[0] > 80


def test_a_model_of_unspecified_sample_time_meets_any_time_index() -> None:
    system, w = noisy_data()
    unspecified = make_ss(system.A, system.B, system.C, system.D, True)
    frame = frame_of(w).set_axis(pd.date_range("2024", periods=len(w), freq="1min"))
    assert abs(misfit(frame, unspecified)[0] - misfit(w, system)[0]) <= 1e-10 * misfit(w, system)[0]


def test_choose_lag_and_misfit_vs_lag_take_frames_by_name() -> None:
    from ident.validation import choose_lag, misfit_vs_lag
    _, w = noisy_data(T=300)
    frame = frame_of(w)
    curve = misfit_vs_lag(frame.iloc[:200], 1, [2], validation=frame.iloc[200:][["position", "force"]])
    curve_arrays = misfit_vs_lag(w[:200], 1, [2], validation=w[200:])
    assert np.allclose(curve.fit, curve_arrays.fit, atol=1e-6) and curve.fit[0] > 80
    choice = choose_lag(frame, 1, [1, 2], exct=["force"])
    assert choice.ell == choose_lag(w, 1, [1, 2], exct=[0]).ell


def test_import_ident_does_not_need_pandas_for_arrays(monkeypatch) -> None:
    import sys
    monkeypatch.setitem(sys.modules, "pandas", None)  # as if not installed: importing it would fail
    _, w = noisy_data(T=100)
    sysh, _, wh, _ = ident(w, 1, 2)
    assert isinstance(wh, np.ndarray) and sysh.input_labels == ["u[0]"]


# -- a chosen order ----------------------------------------------------------------------------------

def test_a_chosen_order_is_a_balanced_truncation_with_its_misfit() -> None:
    _, w = noisy_data(m=1, p=1, ell=4, T=400, noise=0.02, seed=3)
    full, info_full, _, _ = ident(w, 1, 4)
    reduced, info, wh, xini = ident(w, 1, 4, n=2, dt=0.5)
    assert reduced.nstates == 2 and reduced.dt == 0.5 and xini.shape == (2, 1)
    assert info.reduction.identified.nstates == 4
    assert abs(info.reduction.identified_misfit - info_full.M) <= 1e-6 * info_full.M
    M, _, _ = misfit(w, reduced)
    assert abs(info.M - M) <= 1e-8 * M and info.M >= info_full.M * (1 - 1e-8)
    assert abs(float(np.sum((w - wh) ** 2)) - info.M) <= 1e-6 * info.M
    assert len(info.reduction.singular_values) == 4 and info.reduction.method == "balanced truncation"
    same, info_same, _, _ = ident(w, 1, 4, n=4)
    assert same.nstates == 4 and info_same.reduction is None


def test_an_unstable_identified_model_is_reduced_by_the_better_of_keeping_and_dropping() -> None:
    rng = np.random.default_rng(1)
    A = np.diag([0.8, -0.6, 1.02])  # one unstable mode of small weight
    model = make_ss(A, np.array([[1.0], [0.7], [1e-3]]), np.array([[1.0, 0.5, 1e-3]]), np.zeros((1, 1)))
    u = rng.standard_normal((200, 1))
    w = np.hstack([u, simulate(model, u, np.zeros(3)) + 0.01 * rng.standard_normal((200, 1))])
    kept, dropped = (balanced_truncation(model, 2, unstable=choice).model for choice in ("keep", "drop"))
    assert np.max(np.abs(np.linalg.eigvals(kept.A))) > 1 > np.max(np.abs(np.linalg.eigvals(dropped.A)))
    # the choice ident makes, on the misfit, for this model
    misfits = {"keep": misfit(w, kept)[0], "drop": misfit(w, dropped)[0]}
    assert misfits["drop"] < misfits["keep"]
    with pytest.raises(ValueError, match=r"n = 0 is less than the 1 unstable mode"):
        balanced_truncation(model, 0)
    assert balanced_truncation(model, 0, unstable="drop").model.nstates == 0


def test_balanced_truncation_of_a_model_without_inputs_uses_its_initial_states() -> None:
    system = random_system(0, 2, 2, np.random.default_rng(5))
    x0 = np.array([[1.0], [0.0], [0.0], [0.0]])
    reduced = balanced_truncation(system, 1, x0=x0)
    assert reduced.model.ninputs == 0 and reduced.model.nstates == 1
    free = simulate(system, 300, x0[:, 0])
    assert np.max(reduced.singular_values) > 0
    assert np.all(np.isfinite(simulate(reduced.model, 300, np.ones(1)))) and free.shape == (300, 2)


@pytest.mark.parametrize("n, error, words", [
    (3, ValueError, r"n must satisfy 1 <= n <= 2 = ell \* p"),
    (-1, ValueError, r"n must satisfy 1 <= n <= 2"),
    (0, ValueError, r"n must satisfy 1 <= n <= 2 = ell \* p, the order of the identified model \(a static model is ell = 0"),
    (1.5, TypeError, r"n must be an integer"),
    ("1", TypeError, r"n must be an integer"),
])
def test_a_bad_order_is_refused_by_name(n, error, words) -> None:
    _, w = noisy_data(T=60)
    with pytest.raises(error, match=words):
        ident(w, 1, 2, n=n)


def test_a_chosen_order_with_given_initial_samples_is_refused() -> None:
    _, w = noisy_data(T=60)
    with pytest.raises(ValueError, match=r"n = 1: a reduced model has another lag"):
        ident(w, 1, 2, n=1, wini=np.zeros((2, 2)))
    assert ident(w, 1, 2, n=1, wini=0)[0].nstates == 1


# -- compare and resid -------------------------------------------------------------------------------

def test_compare_is_validate_per_output_and_over_series() -> None:
    system, w = noisy_data(m=2, p=2, ell=1, T=400)
    comparison = compare(w, system)
    single = validate(system, w[:, :2], w[:, 2:])
    assert np.allclose(comparison.fit, single.fit) and comparison.series_fits.shape == (1, 2)
    several = compare([w[:200], w[200:]], system)
    assert several.series_fits.shape == (2, 2) and len(several.yh) == 2
    y = np.vstack([w[:200, 2:], w[200:, 2:]])
    assert np.allclose(several.fit, fit_percent(y, np.vstack(several.yh))[0])
    figure = several.plot()
    assert len(figure.axes) == 2 and figure.axes[0].get_ylabel() == "y[0]"


def test_compare_of_a_model_that_cannot_be_simulated_is_zero_with_the_reason() -> None:
    _, w = noisy_data(T=400)
    unstable = make_ss([[2.0]], [[1.0]], [[1.0]], [[0.0]])
    with warnings_as_errors():
        comparison = compare(w, unstable)
    assert comparison.fit.tolist() == [0.0] and "spectral radius 2" in comparison.reason
    comparison.plot()
    with pytest.raises(ValueError, match="resid: the model cannot be simulated"):
        resid(w, unstable)


def test_resid_shapes_bounds_and_plot() -> None:
    rng = np.random.default_rng(4)
    system = random_system(2, 2, 1, rng)
    u = rng.standard_normal((2000, 2))
    w = np.hstack([u, simulate(system, u) + 0.1 * rng.standard_normal((2000, 2))])  # output noise only
    analysis = resid(w, system, lags=10)
    assert analysis.autocorrelation.shape == (11, 2) and np.allclose(analysis.autocorrelation[0], 1)
    assert analysis.cross_correlation.shape == (21, 2, 2) and analysis.cross_bound.shape == (2, 2)
    assert abs(analysis.auto_bound - 2.5758293035489 / np.sqrt(2000)) < 1e-12
    # the residuals of the true model are the noise: white and independent of the inputs
    assert np.mean(np.abs(analysis.autocorrelation[1:]) > analysis.auto_bound) <= 0.15
    assert np.mean(np.abs(analysis.cross_correlation) > analysis.cross_bound) <= 0.1
    figure = analysis.plot()
    assert len(figure.axes) == 2 * 3


@pytest.mark.parametrize("lags", [0, -1, 300, 2.5, True])
def test_resid_refuses_bad_lags(lags) -> None:
    system, w = noisy_data(T=300)
    with pytest.raises(ValueError, match=r"lags must be an integer with 1 <= lags < T = 300"):
        resid(w, system, lags=lags)


def test_compare_and_resid_check_the_model_against_the_data() -> None:
    system, w = noisy_data()
    with pytest.raises(ValueError, match=r"w has q = 3 variables but sys has 1 inputs and 1 outputs"):
        compare(np.hstack([w, w[:, :1]]), system)
    with pytest.raises(TypeError, match=r"sys must be a discrete-time control.StateSpace"):
        resid(w, "model")


# -- the model file and the command line -------------------------------------------------------------

def identify_file(tmp_path, *options, header=True, capsys=None):
    system, w = noisy_data(T=300)
    data = tmp_path / "data.csv"
    np.savetxt(data, w, delimiter=",", header="force,position" if header else "", comments="")
    model_file = tmp_path / "model.json"
    inputs, outputs = ("force", "position") if header else ("1", "2")
    status = main(["identify", str(data), "--inputs", inputs, "--outputs", outputs, "--lag", "2",
                   "--model", str(model_file), "--plot", str(tmp_path / "fit.png"), *options])
    return status, model_file, w


def test_a_model_file_round_trip(tmp_path) -> None:
    status, model_file, w = identify_file(tmp_path, "--dt", "0.02")
    assert status == 0
    saved = load_model(model_file)
    document = json.loads(model_file.read_text())
    assert saved.model.dt == 0.02 and saved.model.input_labels == ["force"]
    assert saved.model.output_labels == ["position"]
    assert np.allclose(saved.input_means, w[:, 0].mean()) and np.allclose(saved.output_means, w[:, 1].mean())
    assert np.array_equal(np.asarray(saved.model.A), np.array(document["A"]))
    assert saved.info["lag"] == 2 and "fit" in saved.info and "A" not in saved.info
    assert saved.simulate(w[:, :1]).shape == (300, 1)


def test_columns_of_a_file_without_a_header_are_named_column_k(tmp_path) -> None:
    status, model_file, _ = identify_file(tmp_path, header=False)
    saved = load_model(model_file)
    assert status == 0 and saved.model.input_labels == ["column 1"] and saved.model.output_labels == ["column 2"]
    assert saved.model.dt == 1


def test_the_command_line_refuses_a_bad_dt_and_prints_its_version(tmp_path, capsys) -> None:
    status, _, _ = identify_file(tmp_path, "--dt", "0")
    assert status == 2 and "argument --dt: must be a finite positive number" in capsys.readouterr().err
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip().endswith("0.1.0")


@pytest.mark.parametrize("content, words", [
    ("not json", r"cannot read the model file"),
    ('{"A": [[1]]}', r"is not a model file of ident: it has no B, C, D, dt, inputs, outputs, means"),
    ('{"A": [[1, 2]], "B": [[1]], "C": [[1]], "D": [[0]], "dt": 1, "inputs": ["u"], "outputs": ["y"], '
     '"means": {"inputs": [0], "outputs": [0]}}', r"does not describe a model"),
])
def test_load_model_refuses_what_is_not_a_model(tmp_path, content, words) -> None:
    path = tmp_path / "model.json"
    path.write_text(content)
    with pytest.raises(ValueError, match=words):
        load_model(path)


def test_load_model_reads_a_model_without_inputs(tmp_path) -> None:
    from ident.model_file import model_document
    system = random_system(0, 1, 2, np.random.default_rng(2))
    path = tmp_path / "free.json"
    path.write_text(json.dumps(model_document(system, np.zeros(0), np.ones(1))))
    saved = load_model(path)
    assert saved.model.ninputs == 0 and saved.model.nstates == 2
    assert np.allclose(saved.simulate(np.zeros((5, 0)), np.zeros(2)), 1.0)


def test_the_third_order_two_by_two_plant_of_the_issue() -> None:
    """Order 3 with p = 2: ident(w, 2, 2) can only give order 4; n=3 gives the plant's order, and on
    held-out data it simulates as well as the plant (benchmarks/reduction_study.py runs 100 such cases)."""
    rng = np.random.default_rng(21)
    three_outputs = random_system(2, 3, 1, rng)
    plant = make_ss(three_outputs.A, three_outputs.B, three_outputs.C[:2], three_outputs.D[:2])
    u = rng.standard_normal((1000, 2))
    w = np.hstack([u, simulate(plant, u, rng.standard_normal(3))]) + 0.01 * rng.standard_normal((1000, 4))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reduced, info, wh, xini = ident(w[:700], 2, 2, n=3)
    radius = np.max(np.abs(np.linalg.eigvals(info.reduction.identified.A)))
    print(f"order 4: spectral radius {radius:.3f}; order 3: {info.reduction.method}, {info.reduction.misfits}")
    assert reduced.nstates == 3 and np.max(np.abs(np.linalg.eigvals(reduced.A))) < 1
    fit = validate(reduced, w[700:, :2], w[700:, 2:]).mean_fit
    assert fit > validate(plant, w[700:, :2], w[700:, 2:]).mean_fit - 1
    assert info.M <= 1.2 * misfit(w[:700], plant)[0]


# -- issue 31, roles by name and saving models: save_model and load_model round trip -----------------

def test_save_model_round_trips_matrices_names_dt_and_offset_bit_for_bit(tmp_path) -> None:
    from types import SimpleNamespace

    from ident import save_model

    rng = np.random.default_rng(31)
    plant = random_system(2, 1, 3, rng)
    sysh = make_ss(plant.A / 3, plant.B, plant.C, plant.D, 0.025, inputs=["valve", "fan"], outputs=["temp"])
    offset = SimpleNamespace(inputs=np.array([0.1, 1 / 3]), outputs=np.array([np.pi * 1e-7]))  # an Offset's fields
    path = tmp_path / "model.json"
    save_model(path, sysh, offset=offset, info={"lag": 3, "note": "dryer"})
    saved = load_model(path)
    for name in "ABCD":  # the same floats through JSON's repr: equal, not close
        assert np.array_equal(np.asarray(getattr(saved.model, name)), np.asarray(getattr(sysh, name))), name
    assert saved.model.dt == 0.025
    assert list(saved.model.input_labels) == ["valve", "fan"] and list(saved.model.output_labels) == ["temp"]
    assert np.array_equal(saved.input_means, offset.inputs) and np.array_equal(saved.output_means, offset.outputs)
    assert saved.info == {"lag": 3, "note": "dryer"}


def test_save_model_writes_an_identified_model_with_its_info_and_replaces_a_file_whole(tmp_path) -> None:
    from ident import save_model

    _, w = noisy_data()
    sysh, info, _, _ = ident(pd.DataFrame(w, columns=["u", "y"]), 1, 2)
    path = tmp_path / "model.json"
    path.write_text("an older file")
    save_model(str(path), sysh, info=info)
    saved = load_model(path)
    assert np.allclose(saved.input_means, 0) and np.allclose(saved.output_means, 0)
    assert saved.model.input_labels == ["u"] and saved.model.output_labels == ["y"] and saved.model.dt == 1
    assert saved.info["start"] == info.start and saved.info["iterations"] == info.iter
    assert saved.info["misfit"] == pytest.approx(info.M, rel=1e-15)
    assert [p.name for p in tmp_path.iterdir()] == ["model.json"]  # no temporary file left beside it


# -- issue 31, roles by name and saving models: inputs= and outputs= ---------------------------------

def roles_data():
    """w = [u, y1, y2] of a 1-input, 2-output plant, and the same columns reordered [y2, u, y1]."""
    rng = np.random.default_rng(7)
    plant = random_system(1, 2, 1, rng)
    u = rng.standard_normal((300, 1))
    w = np.hstack([u, simulate(plant, u, rng.standard_normal(2))]) + 0.01 * rng.standard_normal((300, 3))
    return w, w[:, [2, 0, 1]]


def test_ident_with_roles_by_position_gives_the_fit_of_the_inputs_first_order_and_wh_in_the_callers() -> None:
    w, shuffled = roles_data()
    sysh, info, wh, xini = ident(w, 1, 1)
    for roles in ({"inputs": [1], "outputs": [2, 0]}, {"inputs": [1]}, {"outputs": [2, 0]}):
        sysh_r, info_r, wh_r, xini_r = ident(shuffled, ell=1, **roles)
        assert sysh_r.ninputs == 1 and sysh_r.noutputs == 2
        assert info_r.M == pytest.approx(info.M, rel=1e-9)  # the outputs' order does not change the misfit
        np.testing.assert_allclose(wh_r, wh[:, [2, 0, 1]], rtol=0, atol=1e-9)  # the caller's column order
        if roles.get("outputs") == [2, 0]:  # the outputs in w's order: the same model, state for state
            np.testing.assert_allclose(xini_r, xini, rtol=0, atol=1e-9)
            np.testing.assert_allclose(sysh_r.C, sysh.C, rtol=0, atol=1e-9)
    assert ident(shuffled, 1, 1, inputs=[1], outputs=[2, 0])[1].M == pytest.approx(info.M, rel=1e-9)  # m agrees


def test_ident_with_roles_by_name_names_the_model_and_maps_exct_and_wini() -> None:
    w, _ = roles_data()
    frame = pd.DataFrame(w, columns=["u", "a", "b"])
    shuffled = frame[["b", "u", "a"]]
    wini = np.ones((1, 3))
    sysh, info, wh, _ = ident(frame, 1, 1, exct=["u"], wini=wini * [1, 2, 3])
    sysh_r, info_r, wh_r, _ = ident(shuffled, ell=1, inputs=["u"], outputs=["a", "b"], exct=["u"],
                                    wini=wini * [3, 1, 2])  # wini's columns are shuffled's too
    assert list(sysh_r.input_labels) == ["u"] and list(sysh_r.output_labels) == ["a", "b"]
    assert info_r.M == pytest.approx(info.M, rel=1e-9)
    assert list(wh_r.columns) == ["b", "u", "a"]
    np.testing.assert_allclose(wh_r[["u", "a", "b"]].to_numpy(), wh.to_numpy(), rtol=0, atol=1e-9)
    assert np.allclose(wh_r["u"], shuffled["u"])  # the exact input is not corrected


def test_compare_with_columns_in_another_order_gives_the_same_fit_as_in_the_models_order() -> None:
    """Issue 31: by name for a named model; by position with inputs=/outputs= for arrays."""
    w, shuffled = roles_data()
    named, _, _, _ = ident(pd.DataFrame(w, columns=["u", "a", "b"]), 1, 1)
    unnamed, _, _, _ = ident(w, 1, 1)
    in_order = compare(pd.DataFrame(w, columns=["u", "a", "b"]), named).fit
    assert np.all(in_order > 90)
    np.testing.assert_allclose(compare(pd.DataFrame(shuffled, columns=["b", "u", "a"]), named).fit, in_order,
                               rtol=1e-12)
    np.testing.assert_allclose(compare(pd.DataFrame(shuffled, columns=["b", "u", "a"]), named, inputs=["u"]).fit,
                               in_order, rtol=1e-12)
    np.testing.assert_allclose(compare(shuffled, unnamed, inputs=[1], outputs=[2, 0]).fit, compare(w, unnamed).fit,
                               rtol=1e-12)
    np.testing.assert_allclose(resid(shuffled, unnamed, inputs=[1], outputs=[2, 0]).autocorrelation,
                               resid(w, unnamed).autocorrelation, rtol=1e-9, atol=1e-12)
    assert misfit(shuffled, unnamed, outputs=[2, 0])[0] == pytest.approx(misfit(w, unnamed)[0], rel=1e-9)


def test_lag_functions_take_roles() -> None:
    from ident import choose_lag, misfit_vs_lag

    w, shuffled = roles_data()
    choice, choice_r = choose_lag(w, 1, range(1, 4)), choose_lag(shuffled, lags=range(1, 4), inputs=[1], outputs=[2, 0])
    assert choice_r.ell == choice.ell
    np.testing.assert_allclose(choice_r.misfits, choice.misfits, rtol=1e-7)
    curve = misfit_vs_lag(w[:200], 1, [1, 2], validation=w[200:])
    curve_r = misfit_vs_lag(shuffled[:200], lags=[1, 2], inputs=[1], outputs=[2, 0], validation=shuffled[200:])
    np.testing.assert_allclose(curve_r.misfit, curve.misfit, rtol=1e-7)
    np.testing.assert_allclose(curve_r.fit, curve.fit, rtol=1e-7)
    frame = pd.DataFrame(shuffled, columns=["b", "u", "a"])
    curve_f = misfit_vs_lag(frame[:200], lags=[1, 2], inputs=["u"], outputs=["a", "b"], validation=frame[200:])
    np.testing.assert_allclose(curve_f.fit, curve.fit, rtol=1e-7)
