"""misfit by the state-space smoother against a dense least-squares reference, and its properties."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.linalg

from conftest import warnings_as_errors
from ident import ident, misfit
from ident import smoothing
from ident.representations import make_ss, observability_index, simulate
from ident.smoothing import MisfitWarning, smoothed_misfit


# --- the reference: the least-squares problem with every response formed ---------------------------
def dense_misfit(model, w, exact=(), past=None, at_rest=False):
    """min over x(1) and the unknown inputs of the squared corrections of the free values of w, with
    the exact values met; past: samples before w (exact), at_rest: x(1) = 0. Returns (M, wh, unique)."""
    n, m = model.nstates, model.ninputs
    q = m + model.noutputs
    past = np.zeros((0, q)) if past is None else past
    w = np.vstack([past, w])
    n_past, n_samples = len(past), len(w)
    observed = ~np.isnan(w)
    exact_values = np.zeros_like(observed)
    exact_values[:, list(exact)] = True
    exact_values[:n_past] = True
    exact_values &= observed
    known = exact_values[:, :m]
    u_known = np.where(known, np.nan_to_num(w[:, :m]), 0.0)
    slots = np.argwhere(~known)

    A, B, C, D = (np.asarray(M, dtype=float) for M in (model.A, model.B, model.C, model.D))

    def trajectory(x1, inputs):  # a plain loop: the reference should share nothing with the smoother
        x, outputs = x1.copy(), np.empty((n_samples, C.shape[0]))
        for t in range(n_samples):
            outputs[t] = C @ x + D @ inputs[t]
            x = A @ x + B @ inputs[t]
        return np.hstack([inputs, outputs]).ravel()

    offset = trajectory(np.zeros(n), u_known)
    columns = [trajectory(e, np.zeros((n_samples, m))) for e in np.eye(n)]
    for t, i in slots:
        inputs = np.zeros((n_samples, m))
        inputs[t, i] = 1.0
        columns.append(trajectory(np.zeros(n), inputs))
    response = np.array(columns).T.reshape(n_samples * q, len(columns))
    data = np.nan_to_num(w).ravel()
    fitted = (observed & ~exact_values).ravel()
    equal = (exact_values & (np.arange(q) >= m)[None, :]).ravel()
    A_eq, b_eq = response[equal], data[equal] - offset[equal]
    if at_rest:
        A_eq, b_eq = np.vstack([A_eq, np.eye(n, len(columns))]), np.r_[b_eq, np.zeros(n)]
    if A_eq.shape[0]:
        theta0 = np.linalg.lstsq(A_eq, b_eq, rcond=None)[0]
        assert np.linalg.norm(A_eq @ theta0 - b_eq) <= 1e-8 * max(1.0, np.linalg.norm(b_eq)), "infeasible"
        null = scipy.linalg.null_space(A_eq)
    else:
        theta0, null = np.zeros(len(columns)), np.eye(len(columns))
    A_ls, b_ls = response[fitted], data[fitted] - offset[fitted]
    y = np.linalg.lstsq(A_ls @ null, b_ls - A_ls @ theta0, rcond=None)[0]
    theta = theta0 + null @ y
    residual = b_ls - A_ls @ theta
    unique = np.linalg.matrix_rank(A_ls @ null) == null.shape[1]
    wh = (response @ theta + offset).reshape(n_samples, q)[n_past:]
    return float(residual @ residual), wh, unique


def random_model(rng, n, m, p, radius=0.9):
    A = rng.standard_normal((n, n))
    if n:
        A *= radius / np.abs(np.linalg.eigvals(A)).max()
    return make_ss(A, rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m)))


def random_models(seed, count, orders=(0, 6), inputs=(0, 3), outputs=(1, 4), radius=0.9):
    """(rng, model) for `count` random models with n, m, p drawn from the half-open ranges given."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        n, m, p = (int(rng.integers(*bounds)) for bounds in (orders, inputs, outputs))
        yield rng, random_model(rng, n, m, p, radius)


def trajectory_of(model, n_samples, rng):
    u = rng.standard_normal((n_samples, model.ninputs))
    return np.hstack([u, simulate(model, u, rng.standard_normal(model.nstates))])


def agree(M, M_reference, w):
    """Relative agreement, with rounding-level misfits measured against the data instead."""
    return abs(M - M_reference) / max(M_reference, 1e-13 * np.nansum(np.asarray(w) ** 2))


SETTINGS = ["errors-in-variables", "output error", "from rest", "missing values", "given initial samples",
            "output error, missing values"]


@pytest.mark.parametrize("setting", SETTINGS)
def test_agrees_with_the_dense_reference_on_random_models(setting) -> None:
    """Orders 0-5 with p = 1-3 outputs (most not a multiple of p), m = 0-2, T = 5-40."""
    rng = np.random.default_rng(SETTINGS.index(setting))
    worst = 0.0
    for _ in range(30):
        n, m, p = int(rng.integers(0, 6)), int(rng.integers(0, 3)), int(rng.integers(1, 4))
        model = random_model(rng, n, m, p)
        lag = observability_index(model) if n else 0
        whole = trajectory_of(model, int(rng.integers(5, 41)) + lag, rng)
        past, w = whole[:lag], whole[lag:] + 0.3 * rng.standard_normal((len(whole) - lag, m + p))
        exact, wini, reference = (), None, {}
        if setting.startswith("output error"):
            exact = tuple(range(m))
            w[:, :m] = whole[lag:, :m]
        if "missing" in setting:
            w[rng.random(w.shape) < 0.2] = np.nan
        if setting == "from rest":
            wini, reference = 0, {"at_rest": True}
        if setting == "given initial samples":
            wini, reference = [past], {"past": past}
        M, wh, _ = misfit(w, model, exct=exact, wini=wini)
        M_dense, wh_dense, unique = dense_misfit(model, w, exact, **reference)
        worst = max(worst, agree(M, M_dense, w))
        if unique:  # where the data determine the trajectory, it is the same
            assert np.abs(wh - wh_dense).max() <= 1e-7 * np.nanmax(np.abs(w)), (n, m, p)
        observed_free = ~np.isnan(w)
        observed_free[:, list(exact)] = False
        assert np.sum((w - wh)[observed_free] ** 2) == pytest.approx(M, rel=1e-7, abs=1e-12 * np.nansum(w ** 2))
    assert worst <= 1e-8


def test_exact_trajectories_give_zero_misfit_and_come_back() -> None:
    for rng, model in random_models(5, 40, orders=(0, 7)):
        w = trajectory_of(model, int(rng.integers(5, 300)), rng)
        M, wh, _ = misfit(w, model)
        assert M <= 1e-18 * np.sum(w ** 2)
        assert np.abs(wh - w).max() <= 1e-9 * np.abs(w).max()


def test_missing_values_of_an_exact_trajectory_are_filled_in() -> None:
    for rng, model in random_models(19, 40, orders=(0, 5)):
        w = trajectory_of(model, int(rng.integers(10, 41)), rng)
        holes = w.copy()
        holes[rng.random(w.shape) < 0.3] = np.nan
        M, completed, _ = misfit(holes, model)
        assert M <= 1e-18 * np.nansum(holes ** 2)
        if dense_misfit(model, holes)[2]:  # where the values left determine the trajectory, it is w
            assert np.abs(completed - w).max() <= 1e-7 * np.abs(w).max()


def test_exact_outputs_where_the_model_can_meet_them() -> None:
    for rng, model in random_models(6, 30, orders=(1, 5), inputs=(1, 3), outputs=(2, 4)):
        m = model.ninputs
        w0 = trajectory_of(model, int(rng.integers(10, 40)), rng)
        w = w0 + 0.3 * rng.standard_normal(w0.shape)
        w[:, m] = w0[:, m]  # the first output is exact and a value of a trajectory
        M, wh, _ = misfit(w, model, exct=[m])
        M_dense, wh_dense, unique = dense_misfit(model, w, (m,))
        assert agree(M, M_dense, w) <= 1e-7
        assert np.array_equal(wh[:, m], w[:, m])
        if unique:  # some of these models have unstable zeros: the dense reference inverts them too
            assert np.abs(wh - wh_dense).max() <= 1e-5 * np.abs(w).max()


def test_exact_outputs_the_model_cannot_meet_name_exct() -> None:
    rng = np.random.default_rng(7)
    model = random_model(rng, 2, 1, 2)
    w = rng.standard_normal((50, 3))
    with pytest.raises(ValueError, match="exct: no trajectory of sysh meets the exact values of series 0"):
        misfit(w, model, exct=[1, 2])
    past = rng.standard_normal((observability_index(model) + 3, 3))
    with pytest.raises(ValueError, match="wini must be|wini\\[0\\] must be"):
        misfit(w, model, wini=[past])  # more samples than the lag: refused by shape


def test_several_series_add_up() -> None:
    rng = np.random.default_rng(8)
    model = random_model(rng, 3, 1, 2)
    series = [trajectory_of(model, T, rng) + 0.1 * rng.standard_normal((T, 3)) for T in (20, 35, 50)]
    M, wh, xini = misfit(series, model)
    parts = [misfit(w, model) for w in series]
    assert M == pytest.approx(sum(part[0] for part in parts), rel=1e-12)
    assert xini.shape == (3, 3)
    for k, part in enumerate(parts):
        np.testing.assert_allclose(wh[k], part[1], rtol=0, atol=1e-12 * np.abs(series[k]).max())
        np.testing.assert_allclose(xini[:, k], part[2][:, 0], rtol=1e-9, atol=1e-12)


def test_initial_state_reproduces_the_trajectory() -> None:
    rng = np.random.default_rng(9)
    model = random_model(rng, 4, 2, 1)
    w = trajectory_of(model, 200, rng) + 0.2 * rng.standard_normal((200, 3))
    M, wh, xini = misfit(w, model)
    y = simulate(model, wh[:, :2], xini[:, 0])
    assert np.abs(y[:, 0] - wh[:, 2]).max() < 1e-10 * np.abs(w).max()


def test_similarity_transforms_change_only_rounding() -> None:
    for rng, model in random_models(10, 20, orders=(1, 7)):
        n, q = model.nstates, model.ninputs + model.noutputs
        w = trajectory_of(model, 150, rng) + 0.2 * rng.standard_normal((150, q))
        M = misfit(w, model)[0]
        for T in (np.linalg.qr(rng.standard_normal((n, n)))[0], np.diag(2.0 ** rng.integers(-40, 40, n)),
                  np.diag(10.0 ** rng.uniform(-6, 6, n))):
            T_inv = np.linalg.inv(T)
            transformed = make_ss(T_inv @ model.A @ T, T_inv @ model.B, model.C @ T, model.D)
            assert misfit(w, transformed)[0] == pytest.approx(M, rel=1e-9)
        if n:  # the states in units 1e300 apart: B = 1e300 B, C = 1e-300 C
            extreme = make_ss(model.A, 1e300 * np.asarray(model.B), 1e-300 * np.asarray(model.C), model.D)
            assert misfit(w, extreme)[0] == pytest.approx(M, rel=1e-9)


@pytest.mark.parametrize("c", [2.0 ** -500, 1e-150, 1e-20, 3.7, 1e20, 1e150, 2.0 ** 500])
def test_scaling_the_data_scales_the_misfit_over_the_whole_range(c) -> None:
    rng = np.random.default_rng(11)
    model = random_model(rng, 3, 1, 2)
    w = trajectory_of(model, 100, rng) + 0.1 * rng.standard_normal((100, 3))
    M, wh, xini = misfit(w, model)
    with warnings_as_errors():
        M_c, wh_c, xini_c = misfit(c * w, model)
    assert M_c == pytest.approx(c ** 2 * M, rel=1e-12)
    np.testing.assert_allclose(wh_c, c * wh, rtol=1e-12, atol=1e-12 * c * np.abs(w).max())
    np.testing.assert_allclose(xini_c, c * xini, rtol=1e-9, atol=1e-12 * c * np.abs(xini).max())


@pytest.mark.parametrize("c", [1e200, 1e-200])
def test_a_misfit_beyond_the_range_is_said_and_the_trajectory_is_still_right(c) -> None:
    rng = np.random.default_rng(12)
    model = random_model(rng, 3, 1, 2)
    w = trajectory_of(model, 100, rng) + 0.1 * rng.standard_normal((100, 3))
    M, wh, _ = misfit(w, model)
    with pytest.warns(MisfitWarning, match="beyond the floating-point range"):
        M_c, wh_c, _ = misfit(c * w, model)
    assert M_c == (np.inf if c > 1 else 0.0)
    assert np.all(np.isfinite(wh_c))
    np.testing.assert_allclose(wh_c, c * wh, rtol=1e-12, atol=1e-12 * c * np.abs(w).max())


def test_the_stationary_shortcut_gives_the_numbers_of_the_step_by_step_smoother(monkeypatch) -> None:
    rng = np.random.default_rng(13)
    model = random_model(rng, 4, 2, 2)
    w = trajectory_of(model, 3000, rng) + 0.1 * rng.standard_normal((3000, 4))
    w[1000:1010, 1] = np.nan  # stretches of other kinds in between
    w[2000:2100:7, 3] = np.nan
    for exact in [(), (0, 1)]:
        fast = smoothed_misfit(model.A, model.B, model.C, model.D, [w], exact)
        monkeypatch.setattr(smoothing, "STATIONARY_TOL", -1.0)  # never held: every sample stepped
        slow = smoothed_misfit(model.A, model.B, model.C, model.D, [w], exact)
        monkeypatch.undo()
        assert fast.misfit == pytest.approx(slow.misfit, rel=1e-8)  # R held once it changes < 1e-10 a sample
        np.testing.assert_allclose(fast.trajectories[0], slow.trajectories[0], rtol=0, atol=1e-9 * np.nanmax(np.abs(w)))


def test_unstable_models_in_output_error_by_reversing_time() -> None:
    """All eigenvalues outside the unit circle: the time-reversed model is stable, and its dense
    output-error problem (free final state) is a well-conditioned reference over 300 samples. The
    trajectory too: its unstable part comes from the future (no MisfitWarning)."""
    rng = np.random.default_rng(14)
    for _ in range(10):
        n, m, p = int(rng.integers(1, 4)), int(rng.integers(1, 3)), int(rng.integers(1, 3))
        A = rng.standard_normal((n, n))
        A *= rng.uniform(1.05, 1.5) / np.abs(np.linalg.eigvals(A)).min()
        B, C, D = rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m))
        w = rng.standard_normal((300, m + p))
        with warnings.catch_warnings():
            warnings.simplefilter("error", MisfitWarning)
            M, wh, _ = misfit(w, make_ss(A, B, C, D), exct=range(m))
        A_inv = np.linalg.inv(A)  # x(t) = A^-1 x(t+1) - A^-1 B u(t), y(t) = C A^-1 x(t+1) + (D - C A^-1 B) u(t)
        reversed_model = make_ss(A_inv, -A_inv @ B, C @ A_inv, D - C @ A_inv @ B)
        M_reversed, wh_reversed, _ = dense_misfit(reversed_model, w[::-1], tuple(range(m)))
        assert M == pytest.approx(M_reversed, rel=1e-8)
        assert np.abs(wh - wh_reversed[::-1]).max() <= 1e-6 * np.abs(w).max()


def test_errors_in_variables_with_an_unstable_model() -> None:
    """With free inputs the smoother's feedback is stable: the trajectory is accurate too."""
    rng = np.random.default_rng(15)
    model = random_model(rng, 3, 1, 2, radius=1.3)
    w = rng.standard_normal((40, 3))
    M, wh, _ = misfit(w, model)
    M_dense, wh_dense, _ = dense_misfit(model, w)
    assert agree(M, M_dense, w) <= 1e-8
    assert np.abs(wh - wh_dense).max() <= 1e-7 * np.abs(w).max()


def test_exact_output_behind_unstable_zero_dynamics(monkeypatch) -> None:
    """The optimal inputs invert an unstable system; the state's growing direction comes from the
    future. Without that (the projection switched off) the trajectory is wrong, and misfit says so."""
    A = np.array([[0.5, 0.0], [0.0, 0.3]])
    B, C, D = np.array([[1.0], [1.0]]), np.array([[1.0, 0.0], [1.0, -2.0]]), np.array([[0.0], [0.02]])
    model = make_ss(A, B, C, D)  # u -> y2 has a zero near 50 (-C_2 B / D_2)
    rng = np.random.default_rng(16)
    w0 = trajectory_of(model, 60, rng)
    w = w0 + 0.1 * rng.standard_normal(w0.shape)
    w[:, 2] = w0[:, 2]
    M_dense, wh_dense, _ = dense_misfit(model, w, (2,))
    with warnings.catch_warnings():
        warnings.simplefilter("error", MisfitWarning)
        M, wh, _ = misfit(w, model, exct=[2])
    assert agree(M, M_dense, w) <= 1e-8
    assert np.abs(wh - wh_dense).max() <= 1e-5 * np.abs(w).max()  # the dense reference inverts it too
    monkeypatch.setattr(smoothing, "FIXED_BY_FUTURE", np.inf)
    with pytest.warns(MisfitWarning, match="inaccurate"):
        M_unprojected, _, _ = misfit(w, model, exct=[2])
    assert M_unprojected == M


def test_ident_takes_missing_values_and_its_misfit_is_misfits() -> None:
    """Since issue 29 ident takes NaN as a missing sample (32-missing-data.md): same misfit as misfit()."""
    w = np.random.default_rng(17).standard_normal((50, 2))
    w[10, 1] = np.nan
    sysh, info, wh, _ = ident(w, 1, 1)
    assert info.M == pytest.approx(misfit(w, sysh)[0], rel=1e-10) and np.all(np.isfinite(wh))


def test_misfit_equals_info_M_for_ident_models() -> None:
    rng = np.random.default_rng(18)
    for m, p, ell, wini in [(1, 1, 2, None), (2, 1, 2, 0), (1, 2, 1, None), (0, 2, 2, None)]:
        model = random_model(rng, ell * p, m, p)
        w = trajectory_of(model, 200, rng) + 0.05 * rng.standard_normal((200, m + p))
        sysh, info, wh, _ = ident(w, m, ell, wini=wini)
        M, wh_again, _ = misfit(w, sysh, wini=wini)
        assert M == pytest.approx(info.M, rel=1e-7)
        assert np.abs(wh_again - wh).max() <= 1e-5 * np.abs(w).max()
