"""Identification from incomplete data (issue 29, literate/32-missing-data.md): missing samples (NaN,
masked entries) and element-wise weights in ident, against exact data, misfit() and a dense
brute-force weighted projection."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from ident import ident, misfit
from ident.representations import markov_parameters, random_system, simulate

EPS = np.finfo(float).eps


def exact_series(system, lengths, rng):
    m, n = system.ninputs, system.nstates
    out = []
    for length in lengths:
        u = rng.standard_normal((length, m))
        out.append(np.hstack([u, simulate(system, u, rng.standard_normal(n))]))
    return out


def determined_gaps(data, system, w, wini=None) -> np.ndarray:
    """The missing samples that the true model fills with their true values (the others, such as a
    first sample missing in every variable under a free initial state, the data do not determine)."""
    filled = misfit(data, system, wini=wini)[1]
    return np.isnan(data) & (np.abs(filled - w) <= 1e-9 * np.abs(w).max())


def markov_distance(a, b, k: int = 60) -> float:
    """Largest difference of the first k Markov parameters, relative to the largest of a's."""
    ha, hb = np.asarray(markov_parameters(a, k)), np.asarray(markov_parameters(b, k))
    return float(np.abs(ha - hb).max() / np.abs(ha).max())


def dense_weighted_misfit(system, w, weights):
    """min sum v (w - wh)^2 over trajectories wh of the model, by one dense least-squares problem in
    (x0, u): the brute force the sparse saddle-point solution must agree with."""
    A, B, C, D = (np.asarray(getattr(system, x), dtype=float) for x in "ABCD")
    n, m = B.shape
    T, q = w.shape
    columns = np.zeros((T, q, n + T * m))  # wh(t) as a linear function of (x0, u(0), ..., u(T-1))
    state = np.hstack([np.eye(n), np.zeros((n, T * m))])
    for t in range(T):
        u_t = np.zeros((m, n + T * m))
        u_t[:, n + t * m:n + (t + 1) * m] = np.eye(m)
        columns[t, :m] = u_t
        columns[t, m:] = C @ state + D @ u_t
        state = A @ state + B @ u_t
    keep = weights.ravel() > 0
    root = np.sqrt(weights.ravel()[keep])
    matrix = columns.reshape(T * q, -1)[keep] * root[:, None]
    rhs = np.nan_to_num(w).ravel()[keep] * root
    solution = np.linalg.lstsq(matrix, rhs, rcond=None)[0]
    return float(np.sum((matrix @ solution - rhs) ** 2))


def test_exact_siso_data_with_600_of_2000_values_missing_are_recovered() -> None:
    rng = np.random.default_rng(11)
    system = random_system(1, 1, 4, rng)
    (w,) = exact_series(system, [1000], rng)
    gaps = rng.choice(w.size, 600, replace=False)
    data = w.copy()
    data.ravel()[gaps] = np.nan
    given = data.copy()
    sysh, info, wh, _ = ident(data, 1, 4)
    np.testing.assert_array_equal(data, given)  # the caller's array is untouched
    assert markov_distance(system, sysh) <= 1e-8
    determined = determined_gaps(data, system, w)  # a gap the data leave open has no true value to find
    assert determined.sum() >= 595
    assert np.abs(wh - w)[determined].max() <= 1e-8 * np.abs(w).max()
    assert info.M <= 1e-20 * np.sum(np.nan_to_num(data) ** 2)


def test_exact_mimo_series_of_three_lengths_with_a_fifth_missing_are_recovered() -> None:
    rng = np.random.default_rng(12)
    system = random_system(2, 2, 2, rng)
    series = exact_series(system, [300, 450, 600], rng)
    data = [np.where(rng.random(w.shape) < 0.2, np.nan, w) for w in series]
    sysh, info, wh, xini = ident(data, 2, 2)
    assert markov_distance(system, sysh) <= 1e-8
    size = max(np.abs(w).max() for w in series)
    for found, w, gappy in zip(wh, series, data):
        determined = determined_gaps(gappy, system, w)
        assert determined.sum() >= 0.9 * np.isnan(gappy).sum()
        assert np.abs(found - w)[determined].max() <= 1e-8 * size
    assert xini.shape == (4, 3)


@pytest.mark.parametrize("exct", [None, [0]])
def test_the_reported_misfit_is_misfits_and_the_brute_force_projections(exct) -> None:
    rng = np.random.default_rng(13)
    system = random_system(1, 1, 2, rng)
    (w,) = exact_series(system, [60], rng)
    noisy = w + 0.05 * rng.standard_normal(w.shape) * ([0.0, 1.0] if exct else 1.0)
    free = [1] if exct else [0, 1]
    gaps = rng.random((60, len(free))) < 0.25
    noisy[:, free] = np.where(gaps, np.nan, noisy[:, free])
    sysh, info, wh, _ = ident(noisy, 1, 2, exct=exct)
    M, wh_misfit, _ = misfit(noisy, sysh, exct=exct)
    assert info.M == pytest.approx(M, rel=1e-10)
    weights = np.where(np.isnan(noisy), 0.0, 1.0)
    if exct:
        weights[:, exct] = 1e12  # the dense projection takes an exact input as a very heavy one
    assert info.M == pytest.approx(dense_weighted_misfit(sysh, noisy, weights), rel=1e-6)
    np.testing.assert_allclose(wh, wh_misfit, atol=1e-8 * np.nanmax(np.abs(noisy)))


def test_element_wise_weights_with_gaps_agree_with_the_brute_force_projection() -> None:
    rng = np.random.default_rng(14)
    system = random_system(1, 1, 2, rng)
    (w,) = exact_series(system, [50], rng)
    noisy = w + 0.05 * rng.standard_normal(w.shape)
    weights = rng.uniform(0.5, 2.0, w.shape)
    weights[rng.random(w.shape) < 0.2] = 0.0
    given = weights.copy()
    sysh, info, wh, _ = ident(noisy, 1, 2, weights=weights)
    np.testing.assert_array_equal(weights, given)
    assert info.M == pytest.approx(dense_weighted_misfit(sysh, noisy, weights), rel=1e-8)
    assert np.all(np.isfinite(wh))


@pytest.mark.parametrize("s", [[2.0, 10.0, 0.5], [1.0, 1.0, 50.0], [1.0, 30.0, 0.2]])
def test_weight_one_over_s_squared_is_scaling_by_s(s) -> None:
    """The same minimum from two problems: refine's polish (26-solver-optimiser.md) takes both to it; the
    cost alone fixed them only to about sqrt(eps) (at s = [1, 30, 0.2] the models were 2.5e-8 apart)."""
    rng = np.random.default_rng(15)
    system = random_system(1, 2, 1, rng)
    (w,) = exact_series(system, [200], rng)
    noisy = w + 0.1 * rng.standard_normal(w.shape)
    s = np.array(s)
    weighted, info_w, wh_w, _ = ident(noisy, 1, 1, weights=1 / s ** 2, refine=1e-12)
    scaled, info_s, wh_s, _ = ident(noisy / s, 1, 1, refine=1e-12)
    # the scaled model maps u/s0 to y/s: the weighted one, rescaled, must be the same model
    back = scaled.__class__(scaled.A, scaled.B / s[0], scaled.C * s[1:, None], scaled.D * s[1:, None] / s[0], 1)
    assert "polished" in info_w.message and "polished" in info_s.message
    assert markov_distance(back, weighted) <= 1e-8
    assert info_w.M == pytest.approx(info_s.M, rel=1e-8)
    np.testing.assert_allclose(wh_w, wh_s * s, atol=1e-8 * np.abs(noisy).max())


def test_std_weights_are_the_inverse_variances_of_the_observed_samples() -> None:
    rng = np.random.default_rng(16)
    system = random_system(1, 1, 1, rng)
    (w,) = exact_series(system, [120], rng)
    noisy = (w + 0.1 * rng.standard_normal(w.shape)) * [1.0, 50.0]
    noisy[5, 1] = np.nan
    by_name = ident(noisy, 1, 1, weights="std")[1]
    by_value = ident(noisy, 1, 1, weights=1 / np.nanstd(noisy, axis=0) ** 2)[1]
    assert by_name.M == pytest.approx(by_value.M, rel=1e-12)


def test_masked_arrays_and_data_frames_are_nan() -> None:
    pd = pytest.importorskip("pandas")
    rng = np.random.default_rng(17)
    system = random_system(1, 1, 2, rng)
    (w,) = exact_series(system, [80], rng)
    noisy = w + 0.05 * rng.standard_normal(w.shape)
    mask = rng.random(w.shape) < 0.15
    with_nan = np.where(mask, np.nan, noisy)
    masked = np.ma.masked_array(noisy.copy(), mask=mask)
    masked.data[mask] = 1e6  # the values under the mask must not count
    frame = pd.DataFrame(with_nan, columns=["u", "y"])
    M = ident(with_nan, 1, 2)[1].M
    assert ident(masked, 1, 2)[1].M == pytest.approx(M, rel=1e-9)
    sysh, info, wh, _ = ident(frame, 1, 2)
    assert info.M == pytest.approx(M, rel=1e-9)
    assert list(wh.columns) == ["u", "y"] and not wh.isna().any().any()


def test_given_initial_samples_with_missing_data() -> None:
    rng = np.random.default_rng(18)
    system = random_system(2, 1, 2, rng)
    (w,) = exact_series(system, [200], rng)
    data = np.where(rng.random(w.shape) < 0.2, np.nan, w)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sysh, info, wh, _ = ident(data[2:], 2, 2, wini=w[:2])
    assert markov_distance(system, sysh) <= 1e-8
    determined = determined_gaps(data[2:], system, w[2:], wini=w[:2])
    assert determined.sum() >= 0.9 * np.isnan(data[2:]).sum()
    assert np.abs(wh - w[2:])[determined | ~np.isnan(data[2:])].max() <= 1e-8 * np.abs(w).max()


@pytest.mark.parametrize("kind", ["per sample", "per variable", "with wini"])
def test_misfit_with_weights_is_the_misfit_ident_reports(kind) -> None:
    rng = np.random.default_rng(19)
    system = random_system(1, 1, 2, rng)
    (w,) = exact_series(system, [50], rng)
    noisy = w + 0.05 * rng.standard_normal(w.shape)
    weights = rng.uniform(0.5, 2.0, w.shape)
    weights[rng.random(w.shape) < 0.2] = 0.0
    wini = None
    if kind == "per variable":
        weights = np.array([1.0, 4.0])
        noisy[3, 1] = np.nan
    elif kind == "with wini":
        noisy, weights, wini = noisy[2:], weights[2:], w[:2]
    given = (noisy.copy(), np.array(weights, copy=True))
    sysh, info, wh, xini = ident(noisy, 1, 2, weights=weights, wini=wini)
    M, wh_misfit, xini_misfit = misfit(noisy, sysh, weights=weights, wini=wini)
    assert info.M == pytest.approx(M, rel=1e-10)
    size = np.nanmax(np.abs(noisy))
    np.testing.assert_allclose(wh, wh_misfit, atol=1e-10 * size)
    np.testing.assert_allclose(xini, xini_misfit, atol=1e-8 * size)
    np.testing.assert_array_equal(noisy, given[0])
    np.testing.assert_array_equal(weights, given[1])


def test_weights_follow_a_data_frames_columns() -> None:
    pd = pytest.importorskip("pandas")
    rng = np.random.default_rng(20)
    system = random_system(1, 2, 1, rng)
    (w,) = exact_series(system, [200], rng)
    w = w + 0.1 * rng.standard_normal(w.shape)
    w[5, 1] = np.nan
    frame = pd.DataFrame(w[:, [1, 0, 2]], columns=["y1", "u", "y2"])  # the input second
    by_array = ident(w, 1, 1, weights=[1.0, 2.0, 3.0])[1].M
    by_vector = ident(frame, ell=1, inputs=["u"], weights=[2.0, 1.0, 3.0])[1].M  # in the frame's order
    by_samples = ident(frame, ell=1, inputs=["u"], weights=np.ones((200, 3)) * [2.0, 1.0, 3.0])[1].M
    assert by_vector == pytest.approx(by_array, rel=1e-10) and by_samples == pytest.approx(by_array, rel=1e-10)


def test_positive_weights_per_sample_go_to_the_solver_and_agree_with_the_brute_force() -> None:
    rng = np.random.default_rng(21)
    system = random_system(1, 1, 2, rng)
    (w,) = exact_series(system, [50], rng)
    noisy = w + 0.05 * rng.standard_normal(w.shape)
    weights = rng.uniform(0.5, 2.0, w.shape)  # no zero: the solver of the complete case, no refinement
    sysh, info, wh, _ = ident(noisy, 1, 2, weights=weights)
    assert "refined on the missing samples" not in info.message
    assert info.M == pytest.approx(dense_weighted_misfit(sysh, noisy, weights), rel=1e-8)
    assert info.M == pytest.approx(misfit(noisy, sysh, weights=weights)[0], rel=1e-10)


def test_auto_weights_are_raw_or_std_by_the_hold_out() -> None:
    from ident import compare
    rng = np.random.default_rng(30)
    system = random_system(1, 2, 1, rng)
    (w,) = exact_series(system, [300], rng)
    w = (w + 0.1 * rng.standard_normal(w.shape)) * [1.0, 1.0, 80.0]  # one output in other units
    split = 210  # ceil(0.7 T): the first 70 % identify, the last 30 % judge
    fits = {choice: np.mean(compare(w[split:], ident(w[:split], 1, 1, weights=choice)[0]).fit)
            for choice in (None, "std")}
    expected = "std" if fits["std"] > fits[None] else None
    assert ident(w, 1, 1, weights="auto")[1].M == pytest.approx(ident(w, 1, 1, weights=expected)[1].M, rel=1e-12)


def test_auto_weights_need_no_hold_out_where_std_only_scales_the_misfit() -> None:
    from ident.incomplete import chosen_weights
    rng = np.random.default_rng(31)
    system = random_system(1, 1, 2, rng)
    (w,) = exact_series(system, [120], rng)
    noisy = w + 0.1 * rng.standard_normal(w.shape)
    calls = []

    def identify(*args, **kwargs):
        calls.append(kwargs.get("weights"))
        return ident(*args, **kwargs)

    # output error with one output: "std" weighs the one free variable, the same problem as raw
    assert chosen_weights(identify, [noisy], "auto", 1, 2, [0], [None], {}) is None and calls == []
    sysh, info, _, _ = ident(noisy, 1, 2, exct=[0], weights="auto")
    assert info.M == pytest.approx(ident(noisy, 1, 2, exct=[0])[1].M, rel=1e-12)
    # errors-in-variables: u and y have different spreads, so the hold-out decides
    assert chosen_weights(identify, [noisy * [1.0, 20.0]], "auto", 1, 2, [], [None], {}) in (None, "std")
    assert calls == [None, "std"]
