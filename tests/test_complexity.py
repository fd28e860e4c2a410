"""Complexity from data (31-complexity.md): (m, ell, n), the observability indices and the input sets
of exact trajectories of random systems of every class, and the noise-aware order."""
from __future__ import annotations

import numpy as np
import pytest

from ident import complexity, io_partitions
from ident.data_complexity import system_with_lags, valid_input_sets
from ident.representations import make_ss, simulate

CLASSES = [(2, (0, 0)), (1, (3,)), (2, (2, 2)), (2, (3, 2, 1)), (0, (2, 2)), (1, (4, 1)), (3, (1,)), (1, (2, 0))]


def trajectories(m, lags, rng, lengths):
    A, B, C, D = system_with_lags(lags, m, rng)
    system, order = make_ss(A, B, C, D), rng.permutation(m + len(lags))
    series = []
    for length in lengths:
        u = rng.standard_normal((length, m))
        series.append(np.hstack([u, simulate(system, u if m else length, rng.standard_normal(sum(lags)))])[:, order])
    where = np.argsort(order)
    return series, {tuple(sorted(int(where[k]) for k in inputs)) for inputs in valid_input_sets(D, m)}


@pytest.mark.parametrize("m, lags", CLASSES, ids=[f"m{m}-lags{'-'.join(map(str, lags))}" for m, lags in CLASSES])
def test_exact_trajectories_give_the_complexity_and_the_input_sets(m, lags) -> None:
    rng = np.random.default_rng(sum(lags) * 10 + m)
    for trial in range(2):
        series, true_sets = trajectories(m, lags, rng, [200] if trial == 0 else [90, 80, 70])
        found = complexity(series)
        assert (found.m, found.ell, found.n) == (m, max(lags), sum(lags))
        assert found.lags == tuple(sorted(lags, reverse=True))
        assert found.ranks[-1] == len(found.ranks) * m + found.n  # the rank formula where it has settled
        partitions = io_partitions(series, m)
        assert {p.inputs for p in partitions if p.valid} == true_sets
        freedoms = [p.freedom for p in partitions]
        assert freedoms == sorted(freedoms, reverse=True) and all(0 <= f <= 1 + 1e-12 for f in freedoms)


def test_the_data_are_not_modified_and_units_do_not_matter() -> None:
    rng = np.random.default_rng(7)
    (w,), _ = trajectories(2, (3, 2, 1), rng, [200])
    kept = w.copy()
    found = complexity(w)
    assert np.array_equal(w, kept)
    rescaled = complexity(w * np.array([1e6, 1e-4, 1.0, 3e3, 1e-8]))
    assert (rescaled.m, rescaled.n, rescaled.lags) == (found.m, found.n, found.lags)


def test_a_short_record_is_refused_not_guessed() -> None:
    rng = np.random.default_rng(8)
    (w,), _ = trajectories(1, (6,), rng, [20])  # widest window 6 block rows: the lag 6 cannot be seen to settle
    with pytest.raises(ValueError, match="too short or not exact enough"):
        complexity(w)


def test_io_partitions_wants_the_number_of_free_variables() -> None:
    rng = np.random.default_rng(9)
    (w,), _ = trajectories(1, (2, 1), rng, [150])
    with pytest.raises(ValueError, match="w has 1 free variables"):
        io_partitions(w, 2)


@pytest.mark.parametrize("m, lags", [(1, (3,)), (2, (2, 2)), (2, (0, 0))], ids=["siso", "mimo-equal", "static"])
def test_noisy_trajectories_give_the_order(m, lags) -> None:
    rng = np.random.default_rng(350 + sum(lags))
    right = 0
    for _ in range(3):
        (w,), _ = trajectories(m, lags, rng, [1000])
        noisy = w + 0.1 * w.std(axis=0) * rng.standard_normal(w.shape)
        right += complexity(noisy, noisy=True).n == sum(lags)
    assert right >= 2  # the benchmark's rate for these classes is above 85 %


def test_white_noise_has_no_state() -> None:
    found = complexity(np.random.default_rng(11).standard_normal((800, 3)), noisy=True)
    assert (found.n, found.ell) == (0, 0)


def test_the_bound_on_the_largest_correlation_is_the_99_percent_point_of_white_noise() -> None:
    from ident.data_complexity import correlations_above_independence, largest_correlation_bound, past_future_correlations
    rng = np.random.default_rng(12)
    records = [rng.standard_normal((1000, 3)) for _ in range(400)]
    largest = np.array([past_future_correlations([w], 2)[0][0] for w in records])  # 6 directions a half
    bound = largest_correlation_bound(6, 6, 997)
    assert abs(np.quantile(largest, 0.99) - bound) <= 0.1 * bound  # Johnstone's approximation of the 99 % point
    assert np.sum(largest > bound) <= 12  # 1 % of 400 is 4
    assert sum(correlations_above_independence([w], 2) > 0 for w in records[:100]) <= 5  # white noise: no state


def test_a_variable_that_is_zero_throughout_adds_no_direction() -> None:
    from ident.data_complexity import past_future_correlations
    rng = np.random.default_rng(13)
    (w,), _ = trajectories(1, (2,), rng, [600])
    w = w + 0.1 * w.std(axis=0) * rng.standard_normal(w.shape)
    with_zero = np.hstack([w, np.zeros((600, 1))])  # an output with no noise that the system keeps at 0
    correlations, past_directions, future_directions, columns = past_future_correlations([with_zero], 3)
    assert (past_directions, future_directions, columns) == (6, 6, 595)
    np.testing.assert_allclose(correlations, past_future_correlations([w], 3)[0], atol=1e-8)
    assert complexity(with_zero, noisy=True).n == complexity(w, noisy=True).n == 2


def test_ident_takes_m_and_ell_from_the_data_when_left_out() -> None:
    from ident import ident
    rng = np.random.default_rng(12)
    A, B, C, D = system_with_lags((2, 2), 1, rng)
    u = rng.standard_normal((500, 1))
    w = np.hstack([u, simulate(make_ss(A, B, C, D), u, rng.standard_normal(4))])
    sysh, info, _, _ = ident(w)  # exact: the exact rule
    assert (sysh.ninputs, sysh.nstates) == (1, 4) and info.complexity.depth > 5
    assert info.M < 1e-12 * np.sum(w ** 2)
    noisy = w + 0.1 * w.std(axis=0) * rng.standard_normal(w.shape)
    sysh, info, _, _ = ident(noisy, ell=2)  # m from the noisy rule, ell as given
    assert (sysh.ninputs, sysh.nstates) == (info.complexity.m, 2 * (3 - info.complexity.m))
    _, info, _, _ = ident(noisy, 1, 2)
    assert info.complexity is None  # both given: nothing found


@pytest.mark.parametrize("output_error", [False, True], ids=["eiv", "oe"])
def test_the_order_inside_the_misfit_is_at_most_the_truncations(output_error) -> None:
    import warnings

    from ident import ident, misfit
    rng = np.random.default_rng(36 + output_error)
    A, B, C, D = system_with_lags((2, 1), 1, rng)
    series = []
    for length in (150, 120):
        u = rng.standard_normal((length, 1))
        w = np.hstack([u, simulate(make_ss(A, B, C, D), u, rng.standard_normal(3))])
        noisy = w + 0.1 * w.std(axis=0) * rng.standard_normal(w.shape)
        if output_error:
            noisy[:, :1] = w[:, :1]
        series.append(noisy)
    exct = [0] if output_error else None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, truncated, _, _ = ident(series, 1, 2, n=3, exct=exct)
        model, fitted, wh, _ = ident(series, 1, 2, n=3, exct=exct, order_fit="misfit")
    assert model.nstates == 3 and fitted.reduction.misfits["balanced truncation"] == pytest.approx(truncated.M, rel=1e-8)
    assert fitted.M <= truncated.M * (1 + 1e-10)
    assert fitted.M == pytest.approx(misfit(series, model, exct=exct)[0], rel=1e-6)  # the model's own misfit
    assert fitted.M == pytest.approx(sum(np.sum((w - x) ** 2) for w, x in zip(series, wh)), rel=1e-6)


@pytest.mark.parametrize("m, lags, ell", [(1, (2, 1), 2), (1, (3,), 4), (2, (2, 2, 1), 2)],
                         ids=["indices-2-1-at-lag-2", "siso-3-at-lag-4", "indices-2-2-1-at-lag-2"])
def test_choose_order_finds_the_order_of_exact_data(m, lags, ell) -> None:
    from ident import choose_order
    rng = np.random.default_rng(40 + sum(lags))
    A, B, C, D = system_with_lags(lags, m, rng)
    u = rng.standard_normal((300, m))
    w = np.hstack([u, simulate(make_ss(A, B, C, D), u, rng.standard_normal(sum(lags)))])
    kept = w.copy()
    choice = choose_order(w, m, ell)
    assert np.array_equal(w, kept)
    assert choice.n == sum(lags) < ell * len(lags)
    assert choice.orders == list(range(1, ell * len(lags) + 1))
    true_index = choice.orders.index(sum(lags))
    assert np.all(choice.holdout_fits[true_index:] > 99.9)  # every order from the true one simulates exactly
    assert choice.holdout_fits[true_index - 1] < 99  # one state fewer cannot
    energy = np.sum(w[:choice.n_estimation] ** 2)
    assert choice.misfits[true_index] < 1e-12 * energy and choice.misfits[true_index - 1] > 1e-6 * energy
    assert choice.n_estimation + choice.n_holdout == len(w)


def test_choose_order_keeps_ell_p_unless_a_lower_order_predicts_better() -> None:
    from ident import choose_order
    rng = np.random.default_rng(44)
    A, B, C, D = system_with_lags((2, 2), 1, rng)  # order ell p = 4: nothing to drop
    u = rng.standard_normal((400, 1))
    w = np.hstack([u, simulate(make_ss(A, B, C, D), u, rng.standard_normal(4))])
    w[:, 1:] += 0.05 * w[:, 1:].std(axis=0) * rng.standard_normal((400, 2))
    choice = choose_order(w, 1, 2, exct=[0])
    assert choice.n == 4
    best_lower = np.nanmax(choice.holdout_fits[:-1])
    assert best_lower <= choice.holdout_fits[-1] + 1.0  # the rule's condition for keeping ell p
    partial = choose_order(w, 1, 2, [1, 3], exct=[0])  # ell p not judged: the smallest within a point of the best
    assert partial.orders == [1, 3] and np.array_equal(partial.holdout_fits, choice.holdout_fits[[0, 2]])


def test_the_order_rule_keeps_ell_p_unless_beaten_by_more_than_a_point() -> None:
    from ident.order_choice import chosen_order
    orders, far = [1, 2, 3, 4], np.array([5.0, 2.0, 1.0, 0.5])  # misfits: no lower order fits as well
    assert chosen_order(orders, np.array([50.0, 80.0, 90.9, 90.0]), far, 1.0, 4) == 4  # 0.9 better: a tie
    assert chosen_order(orders, np.array([50.0, 91.2, 90.5, 90.0]), far, 1.0, 4) == 2  # 1.2 better: reduced
    assert chosen_order(orders, np.array([50.0, 91.2, 91.9, 90.0]), far, 1.0, 4) == 2  # the smallest within a point
    assert chosen_order(orders, np.array([np.nan, np.nan, 95.0, 90.0]), far, 1.0, 4) == 3  # refused orders skipped
    exact = np.array([5.0, 1e-3, 1e-20, 1e-28])  # order 3 fits the estimation part as well as ell p
    assert chosen_order(orders, np.array([50.0, 90.0, 100.0, 100.0]), exact, 1.0, 4) == 3
    assert chosen_order(orders, np.array([50.0, 90.0, 100.0, 100.0]), exact, 1e-12, 4) == 4  # 1e-20 is not tiny there
    assert chosen_order([1, 2, 3], np.array([80.0, 81.0, 79.0]), far[:3], 1.0, 4) == 1  # ell p not among them


def test_a_noisy_free_response_is_read_by_its_singular_values() -> None:
    from ident.data_complexity import free_response_complexity, normalised
    rng = np.random.default_rng(3536)
    right = 0
    for _ in range(4):
        (w,), _ = trajectories(0, (2, 2), rng, [1000])
        noisy = w + 0.1 * w.std(axis=0) * rng.standard_normal(w.shape)
        found = complexity(noisy, noisy=True)
        assert found.m == 0 and found.n <= 4  # the bound on the noise's singular values: no state too many
        right += found.n == 4
    assert right >= 3  # the benchmark's rate for free responses is about 70 %
    (w,), _ = trajectories(1, (3,), rng, [1000])  # an input: the counts above the floor grow with the window
    noisy = w + 0.1 * w.std(axis=0) * rng.standard_normal(w.shape)
    assert free_response_complexity(normalised([noisy])) is None
