"""Stable models when asked (issue 34, 30-uncertainty-and-stability.md): stable=True keeps the spectral
radius within 1 - margin at a price reported in info.stability; with no stable candidate, ident
chooses between the constrained fit and the unstable optimum by a hold-out."""
from __future__ import annotations

import control
import numpy as np
import pytest

from conftest import recorded_warnings
import ident.stability as stability
from ident import UnstableModelWarning, compare, ident, misfit
from ident.stability import clipped
from ident.uncertainty import matched, state_matrix

SLOW_PLANT = control.ss(control.tf([0.05, 0.03], [1, -1.97, 0.975], 1))  # poles of modulus 0.987


def slow_plant_data(seed: int) -> np.ndarray:
    """50 samples, 20 % errors on both variables: at lag 3 every start of "auto" ends unstable."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(50)
    w_true = np.column_stack([u, control.forced_response(SLOW_PLANT, U=u).outputs])
    return w_true + 0.5 * w_true.std(axis=0) * rng.standard_normal(w_true.shape)


def radius(model) -> float:
    return float(np.max(np.abs(model.poles())))


@pytest.mark.parametrize("margin", [1e-3, 0.05])
def test_stable_true_keeps_the_radius_within_the_margin_at_a_reported_price(margin: float) -> None:
    w = slow_plant_data(1)
    with recorded_warnings():
        free, free_info, _, _ = ident(w, 1, 3)
    model, info, wh, _ = ident(w, 1, 3, stable=True, margin=margin)
    report = info.stability
    assert radius(model) <= 1 - margin and np.isclose(report.radius, radius(model), rtol=1e-10)
    assert report.rule == "stable=True" and report.constrained and report.unconstrained_radius > 1
    assert report.misfit_increase > 0 and np.isclose(report.misfit, info.M, rtol=1e-12)
    assert set(report.fits) == {"unconstrained", "constrained"}
    fit_here = float(compare(w, model).fit[0])  # the constrained fit's simulation fit on the same data
    assert abs(report.fits["constrained"] - fit_here) < 1e-6 * max(1.0, abs(fit_here))
    M_model, _, _ = misfit(w, model)  # info.M is the misfit of the model returned
    assert abs(M_model - info.M) <= 1e-6 * info.M
    assert np.isclose(np.sum((w - wh) ** 2), info.M, rtol=1e-6)  # and wh its trajectory


def test_with_no_stable_start_the_hold_out_chooses_and_the_warning_says_which() -> None:
    w = slow_plant_data(1)
    with recorded_warnings() as caught:
        model, info, _, _ = ident(w, 1, 3)
    messages = [str(c.message) for c in caught if issubclass(c.category, UnstableModelWarning)]
    assert len(messages) == 1 and "no start led to a stable model" in messages[0]
    report = info.stability
    assert report.rule == "hold-out" and set(report.holdout) == {"unconstrained", "constrained"}
    chose_stable = report.holdout["constrained"] >= report.holdout["unconstrained"]  # simulation fits, %
    assert report.constrained == chose_stable and (radius(model) < 1) == chose_stable
    assert ("returned it" if chose_stable else "kept the unstable") in messages[0]


def test_an_unstable_plant_keeps_its_unstable_model() -> None:
    rng = np.random.default_rng(3)
    u = rng.standard_normal(150)
    y = control.forced_response(control.ss(control.tf([1.0], [1, -1.03], 1)), U=u).outputs
    w = np.column_stack([u, y]) + 0.05 * np.array([u.std(), y.std()]) * rng.standard_normal((150, 2))
    with recorded_warnings() as caught:
        model, info, _, _ = ident(w, 1, 1, exct=[0])
    assert abs(radius(model) - 1.03) < 0.01 and not info.stability.constrained
    assert info.stability.holdout["unconstrained"] > info.stability.holdout["constrained"]  # simulation fits, %
    assert any("kept the unstable least-misfit model" in str(c.message) for c in caught)


def test_a_stable_optimum_is_left_alone() -> None:
    rng = np.random.default_rng(4)
    u = rng.standard_normal(200)
    w_true = np.column_stack([u, control.forced_response(SLOW_PLANT, U=u).outputs])
    w = w_true + 0.05 * w_true.std(axis=0) * rng.standard_normal(w_true.shape)
    _, plain, _, _ = ident(w, 1, 2)
    model, info, _, _ = ident(w, 1, 2, stable=True)
    assert plain.stability is None and info.stability.rule == "within the bound"
    assert not info.stability.constrained and info.stability.misfit_increase == 0
    assert np.array_equal(info.Rh, plain.Rh) and radius(model) < 1


# The clipped start (the unconstrained optimum with only its unstable poles moved onto the bound)

def random_kernel(rng, p: int, m: int, ell: int) -> np.ndarray:
    kernel = rng.standard_normal((p, (ell + 1) * (m + p)))
    kernel[:, -p:] = -np.eye(p)  # P_ell = I
    return kernel


def poles_of(kernel, m: int, ell: int) -> np.ndarray:
    return np.linalg.eigvals(state_matrix(kernel, m, ell))


@pytest.mark.parametrize("p, m, ell, seed", [(1, 1, 3, 1), (1, 1, 3, 2), (1, 2, 4, 0), (2, 1, 2, 0), (2, 2, 3, 5)])
def test_clipped_moves_the_unstable_poles_onto_the_bound_and_nothing_else(p: int, m: int, ell: int, seed: int) -> None:
    kernel = random_kernel(np.random.default_rng(seed), p, m, ell)
    before, bound = poles_of(kernel, m, ell), 0.999
    unstable = np.abs(before) > bound
    assert unstable.any() and not unstable.all()  # the cases move some poles and keep others
    complex_unstable = np.any(unstable & (np.abs(before.imag) > 1e-12))
    assert complex_unstable == (p == 1)  # complex pairs moved with one output; several: exact for real poles
    moved = clipped(kernel, m, ell, bound)
    expected = np.where(unstable, bound * before / np.abs(before), before)
    after = matched(poles_of(moved, m, ell), expected)
    scale = np.max(np.abs(before))
    assert np.max(np.abs(after - expected)) <= 1e-9 * scale
    blocks, moved_blocks = kernel.reshape(p, ell + 1, -1), moved.reshape(p, ell + 1, -1)
    assert np.array_equal(moved_blocks[:, :, :m], blocks[:, :, :m])  # Q kept
    assert np.array_equal(moved[:, -p:], -np.eye(p))  # P_ell = I kept
    assert np.array_equal(clipped(moved, m, ell, 1.0), moved)  # nothing to move: unchanged
    assert kernel[0, 0] == random_kernel(np.random.default_rng(seed), p, m, ell)[0, 0]  # the caller's array untouched


def unstable_plant_data(seed: int) -> np.ndarray:
    """An unstable plant (poles 1.03 and 0.95), 200 samples, 2 % errors on both variables."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(200)
    plant = control.ss(control.tf([0.1, 0.05], np.poly([1.03, 0.95]), 1))
    w_true = np.column_stack([u, control.forced_response(plant, U=u).outputs])
    return w_true + 0.02 * w_true.std(axis=0) * rng.standard_normal(w_true.shape)


@pytest.mark.parametrize("exact", [None, [0]])
def test_the_clipped_start_never_raises_the_constrained_misfit(exact, monkeypatch) -> None:
    w = unstable_plant_data(7)
    with recorded_warnings():  # the fits may reach maxiter here; the misfits are compared all the same
        model, info, _, _ = ident(w, 1, 2, exct=exact, stable=True)
        starts = stability.constrained_starts
        monkeypatch.setattr(stability, "constrained_starts", lambda *args: starts(*args)[:-1])  # the candidates alone
        try:
            _, candidates_only, _, _ = ident(w, 1, 2, exct=exact, stable=True)
        except ValueError as refused:  # with some BLAS kernels every candidate's fit runs off to a kernel with no model
            assert "no start led to a model within the bound" in str(refused)
            candidates_only = None
    report = info.stability
    assert report.rule == "stable=True" and radius(model) <= 1 - 1e-3 < 1.02 < report.unconstrained_radius
    assert report.start == "the optimum clipped"  # on this record the clipped start leads lower
    assert info.M > report.unconstrained_misfit
    if candidates_only is not None:
        assert candidates_only.stability.start.endswith(", pulled inside") and info.M < candidates_only.M
