"""to_continuous (28-continuous-time.md): the zero-order-hold and Tustin inverses, round trips on
random models with repeated poles and integrators, and the chain of masses in continuous time."""
from __future__ import annotations

import control
import numpy as np
import pytest
import scipy.linalg
import scipy.signal
import threadpoolctl

from ident import ident, to_continuous
from ident.representations import make_ss
from literate_tools.tangled import examples


def random_continuous(rng, kind: str):
    """(A, B, C, D, dt): a random stable continuous model; kind "plain", "jordan" (one Jordan block
    of 2 or more equal poles) or "integrator" (a pole at 0, a discrete pole at 1)."""
    n, m, p = int(rng.integers(2, 9)), int(rng.integers(0, 4)), int(rng.integers(1, 4))
    blocks, size = [], 0
    while size < n:
        if n - size >= 2 and rng.random() < 0.5:
            real, imag = -rng.uniform(0.05, 3), rng.uniform(0.1, 2.5)
            blocks.append(np.array([[real, imag], [-imag, real]]))
            size += 2
        else:
            blocks.append(np.array([[-rng.uniform(0.05, 3)]]))
            size += 1
    J = scipy.linalg.block_diag(*blocks)
    if kind == "jordan":
        k = int(rng.integers(2, n + 1))
        J[:k, :k] = -rng.uniform(0.05, 3) * np.eye(k) + np.diag(np.ones(k - 1), 1)
    elif kind == "integrator":
        J[0, :], J[:, 0] = 0.0, 0.0
    basis = np.linalg.qr(rng.standard_normal((n, n)))[0] * rng.uniform(0.5, 2, n)
    A = basis @ J @ np.linalg.inv(basis)
    return (A, rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m)),
            rng.uniform(0.05, 1.0))


def relative_errors(model, A, B, C, D) -> list[float]:
    return [np.linalg.norm(getattr(model, name) - X) / np.linalg.norm(X)
            for name, X in zip("ABCD", (A, B, C, D)) if X.size and np.linalg.norm(X) > 0]


def test_zero_order_hold_and_back_on_1000_random_systems() -> None:
    rng = np.random.default_rng(2025)
    worst, kinds = 0.0, ["plain", "jordan", "integrator"]
    with threadpoolctl.threadpool_limits(limits=1, user_api="blas"):  # small matrices: threads only cost
        for index in range(1000):
            A, B, C, D, dt = random_continuous(rng, kinds[index % 3])
            A_d, B_d, C_d, D_d, _ = scipy.signal.cont2discrete((A, B, C, D), dt, method="zoh")
            back = to_continuous(make_ss(A_d, B_d, C_d, D_d, dt=dt))
            assert back.dt == 0 and back.B.shape == B.shape
            worst = max(worst, *relative_errors(back, A, B, C, D))
    print(f"worst relative error over 1000 systems: {worst:.1e}")  # 3.2e-14 when written
    assert worst < 1e-10


def test_tustin_and_back() -> None:
    rng = np.random.default_rng(7)
    for index in range(100):
        A, B, C, D, dt = random_continuous(rng, ["plain", "jordan", "integrator"][index % 3])
        A_d, B_d, C_d, D_d, _ = scipy.signal.cont2discrete((A, B, C, D), dt, method="bilinear")  # = "tustin"
        back = to_continuous(make_ss(A_d, B_d, C_d, D_d, dt=dt), method="tustin")
        assert max(relative_errors(back, A, B, C, D)) < 1e-10


def test_a_double_integrator_comes_back() -> None:
    # a Jordan block at 0 in continuous time, at 1 in discrete time: A - I is singular
    model = control.ss([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], [[1.0, 0.0]], [[0.0]])
    back = to_continuous(control.sample_system(model, 0.1))
    assert np.abs(back.A - model.A).max() < 1e-12 and np.abs(back.B - model.B).max() < 1e-12


def test_names_are_kept_and_the_result_is_continuous() -> None:
    model = control.ss([[0.5]], [[1.0]], [[2.0]], [[0.5]], dt=0.2, inputs=["force"], outputs=["position"],
                       states=["x"], name="cart")
    for method in ("zoh", "tustin"):
        back = to_continuous(model, method=method)
        assert back.isctime(strict=True) and back.dt == 0
        assert (back.input_labels, back.output_labels, back.state_labels, back.name) == \
            (["force"], ["position"], ["x"], "cart")


def test_a_model_without_inputs() -> None:
    A_d = np.diag([0.5, 0.8])
    back = to_continuous(make_ss(A_d, np.zeros((2, 0)), [[1.0, 1.0]], np.zeros((1, 0)), dt=2.0))
    assert back.ninputs == 0 and np.allclose(np.diag(back.A), np.log([0.5, 0.8]) / 2, rtol=1e-12, atol=0)


def test_the_chain_of_masses_identified_in_continuous_time() -> None:
    chain = examples.mass_spring_damper_chain()
    physical = np.linalg.eigvals(chain.A)
    assert np.linalg.norm(to_continuous(control.sample_system(chain, 1)).A - chain.A) < 1e-10 * np.linalg.norm(chain.A)
    w = np.loadtxt(examples.reference_path("msd_uy.txt"))
    model, _, _, _ = ident(w, 1, chain.nstates - 1, init="lra", dt=1.0)
    match = examples.match_eigenvalues(np.linalg.eigvals(to_continuous(model).A), physical)
    on_fastest = (np.abs(physical.imag) > 0.95)[match.partner]
    assert match.errors[~on_fastest].max() < 1e-6  # the twelve slower modes and one of the two zeros
    # the fastest pair, weak in these data: within 1e-3 of the physical one (issue 31) because ident realises
    # exact data from a deeper Hankel matrix (the kernel of depth 15 alone holds it to about 2e-3)
    assert match.errors[on_fastest].max() < 1e-4
    assert abs(match.unmatched[0]) < 1e-8


def test_zoh_refuses_a_pole_just_off_the_negative_axis_or_zero_within_the_tolerance() -> None:
    for pole in (-0.5 + 1e-10j, 1e-10):
        A_d = np.array([[pole.real, pole.imag], [-pole.imag, pole.real]]) if isinstance(pole, complex) \
            else np.array([[pole]])
        model = make_ss(A_d, np.ones((len(A_d), 1)), np.ones((1, len(A_d))), [[0.0]], dt=1.0)
        with pytest.raises(ValueError, match="at 0 or on the negative real axis"):
            to_continuous(model)
