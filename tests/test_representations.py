"""Conversions between kernel and input/state/output representations, simulation and inistate
(literate/10-representations.md): round trips, annihilation of trajectories, the non-generic case,
the P_ell checks, the python-control workaround and the accuracy on non-normal observer forms."""
import itertools
import warnings

import control
import numpy as np
import pytest

from conftest import recorded_warnings, warnings_as_errors
from ident.hankel import block_hankel
from ident.representations import (IllConditionedWarning, inistate, kernel_to_ss, make_ss,
                                   markov_parameters, normalize_kernel, observability_index,
                                   observability_matrix, random_system, simulate, ss_to_kernel)

# (m, p, ell) grid including m = 0, ell = 0 and p = 1 (the python-control (1, 0) quirk)
CASES = [(m, p, ell) for m, p, ell in itertools.product([0, 1, 2], [1, 2, 3], [0, 1, 2, 3])]


def kernel_residual(R, w, ell):
    """|| R H_{ell+1}(w) || / (||R|| ||H||)."""
    H = block_hankel(w, ell + 1)
    nH = np.linalg.norm(H)
    return np.linalg.norm(R @ H) / (np.linalg.norm(R) * nH) if nH else 0.0  # w = 0 (m = ell = 0)


def tf_eval(sys, z):
    A, B, C, D = sys.A, sys.B, sys.C, sys.D
    n = A.shape[0]
    return D + (C @ np.linalg.solve(z * np.eye(n) - A, B) if n else 0)


def naive_sim(sys, u, x0):
    A, B, C, D = sys.A, sys.B, sys.C, sys.D
    x = np.array(x0, dtype=float)
    y = []
    for t in range(u.shape[0]):
        y.append(C @ x + D @ u[t])
        x = A @ x + B @ u[t]
    return np.array(y).reshape(u.shape[0], C.shape[0])


def random_kernel(m, p, ell, rng):
    """Random kernel in the normalised chart, multiplied by a random invertible S."""
    q = m + p
    R = rng.standard_normal((p, (ell + 1) * q))
    R[:, ell * q + m:] = -np.eye(p)
    return rng.standard_normal((p, p)) @ R, R


def similar(sys, S):
    Si = np.linalg.inv(S)
    return make_ss(S @ sys.A @ Si, S @ sys.B, sys.C @ Si, sys.D)


# --------------------------------------------------------------------------- make_ss
@pytest.mark.parametrize("n,m,p", list(itertools.product([0, 1, 2], [0, 1, 2], [1, 2])))
def test_make_ss_shapes(n, m, p):
    rng = np.random.default_rng(0)
    A, B = 0.5 * np.eye(n), rng.standard_normal((n, m))
    C, D = rng.standard_normal((p, n)), rng.standard_normal((p, m))
    sys = make_ss(A, B, C, D)
    assert isinstance(sys, control.StateSpace) and control.isdtime(sys, strict=True)
    assert (sys.A.shape, sys.B.shape, sys.C.shape, sys.D.shape) == ((n, n), (n, m), (p, n), (p, m))
    assert (sys.nstates, sys.ninputs, sys.noutputs) == (n, m, p)
    u = rng.standard_normal((7, m))
    x0 = rng.standard_normal(n)
    np.testing.assert_allclose(simulate(sys, u, x0), naive_sim(sys, u, x0), atol=1e-13)


def test_model_whose_output_was_dropped_is_refused():
    """python-control 0.10.2 silently drops the output of an n = 0, m = 0, p = 1 model; make_ss exists
    for that reason, and a model without outputs is refused rather than simulated."""
    s = control.ss(np.zeros((0, 0)), np.zeros((0, 0)), np.zeros((1, 0)), np.zeros((1, 0)), dt=1)
    if s.noutputs != 0:
        pytest.skip("this python-control keeps the output; nothing to refuse")
    with pytest.raises(ValueError, match="no outputs"):
        simulate(s, 3)


# --------------------------------------------------------------------------- round trips
@pytest.mark.parametrize("m,p,ell", CASES)
def test_kernel_ss_kernel(m, p, ell):
    rng = np.random.default_rng(100 * m + 10 * p + ell)
    R, Rn = random_kernel(m, p, ell, rng)
    np.testing.assert_allclose(normalize_kernel(R, m, ell), Rn, atol=1e-10)
    sys = kernel_to_ss(R, m, ell)
    assert (sys.nstates, sys.ninputs, sys.noutputs) == (ell * p, m, p)
    R2 = ss_to_kernel(sys)
    assert R2.shape == R.shape
    np.testing.assert_allclose(R2, Rn, atol=1e-8 * max(1, np.abs(Rn).max()))
    np.testing.assert_allclose(ss_to_kernel(sys, ell=ell), R2)


@pytest.mark.parametrize("m,p,ell", CASES)
def test_ss_kernel_ss(m, p, ell):
    rng = np.random.default_rng(1000 + 100 * m + 10 * p + ell)
    sys = random_system(m, p, ell, rng)
    R = ss_to_kernel(sys)
    assert R.shape == (p, (ell + 1) * (m + p))
    np.testing.assert_allclose(R[:, ell * (m + p) + m:], -np.eye(p), atol=1e-12)  # P_ell = I
    sys2 = kernel_to_ss(R, m, ell)
    assert sys2.nstates == sys.nstates
    np.testing.assert_allclose(markov_parameters(sys2, 40), markov_parameters(sys, 40),
                               atol=1e-9)
    for z in [2.0, -1.5, np.exp(0.3j), 0.5 + 1.2j]:
        np.testing.assert_allclose(tf_eval(sys2, z), tf_eval(sys, z), atol=1e-9)
    # realisations are similar: S = O2^+ O1 maps states of sys to states of sys2
    n = ell * p
    if n:
        O1 = observability_matrix(sys.A, sys.C, ell + 1)
        O2 = observability_matrix(sys2.A, sys2.C, ell + 1)
        np.testing.assert_allclose(O2 @ np.linalg.pinv(O2) @ O1, O1, atol=1e-9)  # same free responses
        S = np.linalg.lstsq(O2, O1, rcond=None)[0]
        Si = np.linalg.inv(S)
        np.testing.assert_allclose(S @ sys.A @ Si, sys2.A, atol=1e-8)
        np.testing.assert_allclose(S @ sys.B, sys2.B, atol=1e-8)
        np.testing.assert_allclose(sys.C @ Si, sys2.C, atol=1e-8)
    np.testing.assert_allclose(sys2.D, sys.D, atol=1e-12)


@pytest.mark.parametrize("seed", range(60))
def test_round_trips_random(seed):
    """Random (m, p, ell) and system per seed: ss -> R -> ss -> R, Markov parameters preserved."""
    rng = np.random.default_rng(seed)
    m, p, ell = int(rng.integers(0, 4)), int(rng.integers(1, 4)), int(rng.integers(0, 5))
    sys = random_system(m, p, ell, rng)
    R = ss_to_kernel(sys)
    sys2 = kernel_to_ss(R, m, ell)
    np.testing.assert_allclose(ss_to_kernel(sys2), R, atol=1e-7 * max(1, np.abs(R).max()))
    # the kernel chart is ill-conditioned when O_ell is: allow eps-ish * cond(O_ell)^2
    c = np.linalg.cond(observability_matrix(sys.A, sys.C, ell)) if ell else 1.0
    H = markov_parameters(sys, 20)
    np.testing.assert_allclose(markov_parameters(sys2, 20), H,
                               atol=1e-12 * c**2 * max(1, np.abs(H).max(initial=0)))


# --------------------------------------------------------------------------- kernel annihilates trajectories
@pytest.mark.parametrize("m,p,ell", CASES)
def test_kernel_annihilates_trajectories(m, p, ell):
    rng = np.random.default_rng(7 + 100 * m + 10 * p + ell)
    sys = random_system(m, p, ell, rng)
    T = 200
    u, x0 = rng.standard_normal((T, m)), rng.standard_normal(ell * p)
    w = np.hstack([u, simulate(sys, u, x0)])
    assert kernel_residual(ss_to_kernel(sys), w, ell) < 1e-10
    # and the other direction: trajectories of kernel_to_ss(R) satisfy R
    R, _ = random_kernel(m, p, ell, rng)
    R[:, : ell * (m + p)] *= 0.3  # keep P(z) moderate so that the response stays bounded
    sys2 = kernel_to_ss(R, m, ell)
    T = 30
    u, x0 = rng.standard_normal((T, m)), rng.standard_normal(ell * p)
    w = np.hstack([u, simulate(sys2, u, x0)])
    assert kernel_residual(R, w, ell) < 1e-10


def test_non_generic_lag_structure():
    """p = 2, n = 3: observability indices (2, 1); rows of minimal degree, P_ell singular."""
    rng = np.random.default_rng(3)
    A = np.diag([0.5, -0.6, 0.7])
    sys = make_ss(A, rng.standard_normal((3, 1)), rng.standard_normal((2, 3)),
                  rng.standard_normal((2, 1)))
    assert observability_index(sys) == 2
    R = ss_to_kernel(sys)
    assert R.shape == (2, 9)
    degrees = [max(i for i in range(3) if np.abs(r[i * 3:(i + 1) * 3]).max() > 1e-12) for r in R]
    assert sorted(degrees) == [1, 2]  # sum of row degrees = n
    u = rng.standard_normal((100, 1))
    w = np.hstack([u, simulate(sys, u, rng.standard_normal(3))])
    assert kernel_residual(R, w, 2) < 1e-10
    with pytest.raises(ValueError, match="singular"):
        kernel_to_ss(R, 1, 2)


def test_ell_larger_than_index_and_static_with_lag():
    rng = np.random.default_rng(4)
    sys = random_system(1, 1, 2, rng)
    R = ss_to_kernel(sys, ell=4)
    assert R.shape == (1, 10) and np.abs(R[:, 6:]).max() == 0  # degree-2 row, padded
    np.testing.assert_allclose(R[:, :6] / -R[0, 5], ss_to_kernel(sys), atol=1e-10)
    static = make_ss(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), [[1.0, 2.0]])
    np.testing.assert_allclose(ss_to_kernel(static), [[1.0, 2.0, -1.0]])
    with pytest.raises(ValueError, match="observability index"):
        ss_to_kernel(sys, ell=1)


# --------------------------------------------------------------------------- inistate
@pytest.mark.parametrize("m,p,ell", [c for c in CASES if c[2] > 0])
def test_inistate(m, p, ell):
    rng = np.random.default_rng(11 + 100 * m + 10 * p + ell)
    sys = random_system(m, p, ell, rng)
    T = 50
    u, x0 = rng.standard_normal((T, m)), rng.standard_normal(ell * p)
    y = simulate(sys, u, x0)
    np.testing.assert_allclose(inistate(np.hstack([u, y]), sys), x0, atol=1e-9)
    np.testing.assert_allclose(inistate(u, y, sys), x0, atol=1e-9)
    S = rng.standard_normal((ell * p, ell * p)) + 3 * np.eye(ell * p)
    sysS = similar(sys, S)
    np.testing.assert_allclose(simulate(sysS, u, S @ x0), y, atol=1e-9)
    np.testing.assert_allclose(inistate(u, y, sysS), S @ x0, atol=1e-8)


def test_inistate_static_autonomous_and_short():
    rng = np.random.default_rng(5)
    sys = random_system(2, 1, 0, rng)
    assert inistate(rng.standard_normal((5, 3)), sys).shape == (0,)
    sys = random_system(0, 2, 2, rng)
    x0 = rng.standard_normal(4)
    y = simulate(sys, 20, x0)
    np.testing.assert_allclose(inistate(None, y, sys), x0, atol=1e-10)
    np.testing.assert_allclose(inistate(y, sys), x0, atol=1e-10)
    with pytest.warns(IllConditionedWarning, match="rank"):
        inistate(None, y[:1], sys)  # T p = 2 < n = 4
    with pytest.raises(TypeError):
        inistate(y)


# --------------------------------------------------------------------------- P_ell checks
@pytest.mark.parametrize("m,p,ell", [(1, 1, 2), (0, 2, 1), (2, 2, 0)])
def test_singular_and_near_singular_P_ell(m, p, ell):
    rng = np.random.default_rng(6)
    _, R = random_kernel(m, p, ell, rng)
    q = m + p
    Rs = R.copy()
    Rs[:, ell * q + m:] = 0.0
    with pytest.raises(ValueError, match="singular"):
        kernel_to_ss(Rs, m, ell)
    with pytest.raises(ValueError, match="singular"):
        normalize_kernel(Rs, m, ell)
    Rn = R.copy()
    Rn[:, ell * q + m:] = -np.diag([1.0] * (p - 1) + [1e-10])
    with pytest.warns(IllConditionedWarning, match=r"condition number .* = [0-9.]+e\+10"):
        kernel_to_ss(Rn, m, ell)
    with warnings_as_errors():
        kernel_to_ss(R, m, ell)  # well conditioned: no warning


# --------------------------------------------------------------------------- validation
def test_validation_errors():
    rng = np.random.default_rng(8)
    sys = random_system(1, 1, 2, rng)
    with pytest.raises(TypeError):
        ss_to_kernel(control.ss2tf(sys))
    with pytest.raises(TypeError):
        ss_to_kernel(np.eye(2))
    with pytest.raises(ValueError, match="discrete"):
        ss_to_kernel(control.ss(sys.A, sys.B, sys.C, sys.D))  # continuous time
    with pytest.raises(ValueError):
        kernel_to_ss(np.ones((1, 5)), 1, 2)  # 5 columns, not a multiple of 3
    with pytest.raises(ValueError, match="outputs"):
        kernel_to_ss(np.ones((1, 6)), 1, 1)  # q = 3, m = 1 -> p = 2, but R has 1 row
    with pytest.raises(ValueError):
        make_ss(np.eye(2), np.ones((3, 1)), np.ones((1, 2)), np.ones((1, 1)))
    with pytest.raises(ValueError):
        simulate(sys, np.ones((5, 2)))
    with pytest.raises(ValueError):
        simulate(sys, np.ones((5, 1)), np.ones(3))


# --------------------------------------------------------------------------- building blocks
def test_observability_and_markov_against_naive():
    rng = np.random.default_rng(9)
    sys = random_system(2, 2, 3, rng)
    A, B, C, D = sys.A, sys.B, sys.C, sys.D
    for k in [0, 1, 2, 5, 13]:
        On = np.vstack([C @ np.linalg.matrix_power(A, i) for i in range(k)]) if k else np.zeros((0, 6))
        np.testing.assert_allclose(observability_matrix(A, C, k), On, atol=1e-12)
    H = markov_parameters(sys, 6)
    np.testing.assert_allclose(H[0], D)
    for i in range(1, 6):
        np.testing.assert_allclose(H[i], C @ np.linalg.matrix_power(A, i - 1) @ B, atol=1e-12)
    assert markov_parameters(random_system(0, 2, 1, rng), 4).shape == (4, 2, 0)


@pytest.mark.parametrize("radius", [(0.3, 0.95), (0.995, 0.9999)])
def test_simulate_against_loop(radius):
    rng = np.random.default_rng(10)
    sys = random_system(2, 2, 2, rng, radius=radius)
    T = 3000
    u, x0 = rng.standard_normal((T, 2)), rng.standard_normal(4)
    y = simulate(sys, u, x0)
    y0 = naive_sim(sys, u, x0)
    assert np.abs(y - y0).max() < 1e-12 * np.abs(y0).max()
    assert simulate(sys, 0).shape == (0, 2)


@pytest.mark.parametrize("m,p,ell", [(0, 1, 0), (1, 2, 0), (1, 1, 3), (2, 3, 2), (0, 2, 3)])
def test_random_system(m, p, ell):
    s1 = random_system(m, p, ell, 42)
    s2 = random_system(m, p, ell, np.random.default_rng(42))
    np.testing.assert_array_equal(s1.A, s2.A)
    assert (s1.nstates, s1.ninputs, s1.noutputs) == (ell * p, m, p)
    assert control.isdtime(s1, strict=True) and s1.dt == 1
    if ell:
        assert np.abs(np.linalg.eigvals(s1.A)).max() < 1
    assert observability_index(s1) == ell


@pytest.mark.parametrize("radius,T", [((0.05, 0.3), 3000), ((0.995, 0.9999), 3000),
                                      ((1.01, 1.05), 60)])
def test_inistate_fast_slow_and_unstable(radius, T):
    """Exercises the truncation of O_T (fast decay) and its absence (slow / unstable)."""
    rng = np.random.default_rng(12)
    sys = random_system(1, 2, 2, rng, radius=radius)
    u, x0 = rng.standard_normal((T, 1)), rng.standard_normal(4)
    y = simulate(sys, u, x0)
    np.testing.assert_allclose(inistate(u, y, sys), x0, atol=1e-8)


def test_simulate_matches_python_control():
    rng = np.random.default_rng(13)
    sys = random_system(2, 2, 2, rng)
    T = 50
    u, x0 = rng.standard_normal((T, 2)), rng.standard_normal(4)
    resp = control.forced_response(sys, T=np.arange(T), U=u.T, X0=x0)
    np.testing.assert_allclose(simulate(sys, u, x0), resp.outputs.T, atol=1e-12)


def test_ss_to_kernel_warns_near_non_generic():
    """n = 2, p = 2 with C nearly rank one: observability indices (1, 1) but close to (2, 0)."""
    A = np.array([[0.5, 1.0], [0.0, 0.6]])
    C = np.array([[1.0, 0.0], [1.0, 1e-10]])
    sys = make_ss(A, np.ones((2, 1)), C, np.zeros((2, 1)))
    with pytest.warns(IllConditionedWarning, match="unnormalised"):
        R = ss_to_kernel(sys, ell=1)
    w = np.hstack([np.ones((10, 1)), simulate(sys, np.ones((10, 1)), [1.0, -1.0])])
    assert kernel_residual(R, w, 1) < 1e-10


def _ill_conditioned_pair():
    """A random system with cond(O_ell) ~ 1e5 and its observer form (||A|| ~ 8e3, transients
    ||A^k|| ~ 2e7): the case where doubling/matrix powers in the original coordinates lost
    all accuracy (Markov parameters off by 1e5, simulation by 1e41)."""
    rng = np.random.default_rng(2129)
    m, p, ell = (int(rng.integers(0, k)) for k in (4, 4, 5))
    sys = random_system(m, p, ell, rng)
    return sys, kernel_to_ss(ss_to_kernel(sys), m, ell), m, p, ell


def test_non_normal_observer_form_is_simulated_accurately():
    sys, obs, m, p, ell = _ill_conditioned_pair()
    assert (m, p, ell) == (2, 3, 3) and np.linalg.norm(obs.A, 2) > 1e3
    rng = np.random.default_rng(0)
    for T in [500, 20000]:
        u = rng.standard_normal((T, m))
        y = simulate(sys, u)  # normal A: accurate
        y2 = simulate(obs, u)
        assert np.abs(y2 - y).max() < 1e-7 * np.abs(y).max()
    H = markov_parameters(sys, 60)
    assert np.abs(markov_parameters(obs, 60) - H).max() < 1e-7 * np.abs(H).max()
    O1, O2 = observability_matrix(sys.A, sys.C, 3000), observability_matrix(obs.A, obs.C, 3000)
    S = np.linalg.lstsq(O2[:40], O1[:40], rcond=None)[0]  # obs state = S sys state
    assert np.abs(O2 @ S - O1).max() < 1e-7 * np.abs(O1).max()
    x0 = rng.standard_normal(ell * p)
    u = rng.standard_normal((3000, m))
    y = simulate(sys, u, x0)
    np.testing.assert_allclose(inistate(u, y, obs), S @ x0, rtol=1e-6, atol=1e-6 * np.abs(S @ x0).max())


def test_kernel_is_read_off_an_observer_form_exactly():
    from ident.representations import observer_form_kernel
    rng = np.random.default_rng(12)
    for m, p, ell in [(1, 1, 3), (2, 2, 2), (0, 2, 2), (1, 3, 1)]:
        R = normalize_kernel(rng.standard_normal((p, (ell + 1) * (m + p))), m, ell)
        sys = kernel_to_ss(R, m, ell)
        read_off = observer_form_kernel(*(np.asarray(x, dtype=float) for x in (sys.A, sys.B, sys.C, sys.D)), ell)
        np.testing.assert_allclose(read_off, R, rtol=0, atol=1e-14 * np.abs(R).max())
        np.testing.assert_allclose(ss_to_kernel(sys), R, rtol=0, atol=1e-14 * np.abs(R).max())
    other = random_system(1, 1, 2, rng)  # not in observer form: no read-off
    assert observer_form_kernel(*(np.asarray(x, dtype=float) for x in (other.A, other.B, other.C, other.D)), 2) is None


def test_ill_conditioning_warnings_point_at_the_callers_line() -> None:
    import warnings

    from ident.representations import IllConditionedWarning, kernel_to_ss

    nearly_singular = np.array([[0.3, 1.0, 1e-10, -1e-10]])  # m = 1, ell = 1: P_1 = 1e-10
    with recorded_warnings() as caught:
        kernel_to_ss(nearly_singular, 1, 1)
    assert [w.category for w in caught] == [IllConditionedWarning]
    assert caught[0].filename == __file__
