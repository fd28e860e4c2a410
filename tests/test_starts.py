"""Tests of the initial approximations (ident.starts)."""
import numpy as np
import pytest

from ident import starts
from ident.hankel import block_hankel
from ident.structure import Structure


def arx_data(n_samples=100, seed=0):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n_samples)
    y = np.zeros(n_samples)
    for t in range(n_samples - 2):
        y[t + 2] = 1.2 * y[t + 1] - 0.5 * y[t] + 0.7 * u[t + 1] + 0.2 * u[t]
    return np.column_stack([u, y])


def test_least_squares_kernel_recovers_an_exact_arx_system():
    w = arx_data()
    structure = Structure.time_major(2, 2, [len(w) - 2])
    R = starts.least_squares(structure.params_from_series([w]), structure, 5)
    assert np.allclose(R, [[0.2, -0.5, 0.7, 1.2, 0.0, -1.0]], atol=1e-10 * np.abs(w).max())


def test_least_squares_is_the_regression_of_the_last_rows_on_the_hankel_matrix():
    # the same numbers as the regression written on block_hankel(w) directly (the DAISY runner's start)
    rng = np.random.default_rng(1)
    w = rng.standard_normal((60, 3))
    structure = Structure.time_major(3, 2, [58])
    hankel = block_hankel(w, 3)
    theta = np.linalg.lstsq(hankel[:-2].T, hankel[-2:].T, rcond=None)[0].T
    R = starts.least_squares(structure.params_from_series([w]), structure, 7)
    assert np.array_equal(R, np.hstack([theta, -np.eye(2)]))


def test_unstructured_lra_spans_the_left_null_space_of_exact_data():
    w = arx_data(seed=2)
    structure = Structure.time_major(2, 2, [len(w) - 2])
    p = structure.params_from_series([w])
    R = starts.start("lra", p, structure, 5)
    H = structure.hankel(p)
    assert R.shape == (1, 6) and np.isclose(np.linalg.norm(R), 1.0)
    assert np.linalg.norm(R @ H) <= 1e-12 * np.linalg.norm(H)


def test_triangular_factor_of_several_series_with_a_permutation():
    rng = np.random.default_rng(3)
    structure = Structure((3, 2, 3), (12, 9), perm=tuple(rng.permutation(8)))
    p = rng.standard_normal(structure.n_params)
    F = starts.hankel_triangular_factor(p, structure, chunk=5)  # several chunks per series
    H = structure.hankel(p)
    assert np.allclose(F.T @ F, H @ H.T, rtol=1e-12, atol=1e-12 * np.abs(H).max() ** 2)


def test_default_starts_in_order_and_reproducible():
    w = arx_data(seed=4)
    structure = Structure.time_major(2, 2, [len(w) - 2])
    p = structure.params_from_series([w])
    first = list(starts.default_starts(p, structure, 5))
    second = list(starts.default_starts(p, structure, 5))
    assert [name for name, _ in first] == ["unstructured LRA", "perturbed LRA (eps=0.001)",
                                          "perturbed LRA (eps=0.1)", "least squares [X, -I]"]
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(first, second))


def test_unknown_start_is_named():  # noqa: F811
    structure = Structure.time_major(2, 1, [10])
    with pytest.raises(ValueError, match="unknown start .ssa."):
        starts.start("ssa", np.zeros(structure.n_params), structure, 3)


# --- the subspace start ---------------------------------------------------------------------------------

from ident.representations import kernel_to_ss, markov_parameters, normalize_kernel, random_system, simulate, \
    ss_to_kernel  # noqa: E402


def system_data(m, p, ell, n_samples, noise, seed):
    rng = np.random.default_rng(seed)
    system = random_system(m, p, ell, rng)
    u = rng.standard_normal((n_samples, m))
    y = simulate(system, u, rng.standard_normal(ell * p))
    return system, np.hstack([u, y + noise * rng.standard_normal(y.shape)])


def subspace_of(w, m, ell):
    structure = Structure.time_major(w.shape[1], ell, [len(w) - ell])
    p = structure.params_from_series([w])
    return starts.subspace(p, structure, structure.n_rows - (w.shape[1] - m)), structure, p


def dense_n4sid(w, m, ell, i):
    """N4SID on the dense block-Hankel matrices, written from the textbook formulas (the reference)."""
    q = w.shape[1]
    p_out, n = q - m, ell * (q - m)
    H = block_hankel(w, 2 * i)  # time-major rows: sample k of the window at rows k q .. k q + q - 1

    def rows(lags, variables):
        return H[[lag * q + v for lag in lags for v in variables]]

    def oblique(past):
        Uf, Wp, Yf = rows(range(past, 2 * i), range(m)), rows(range(past), range(q)), \
            rows(range(past, 2 * i), range(m, q))
        projector = np.eye(H.shape[1]) - (np.linalg.pinv(Uf) @ Uf if m else 0)  # onto the complement of U_f
        return Yf @ projector @ Wp.T @ np.linalg.pinv(Wp @ projector @ Wp.T) @ Wp

    U, s, Vt = np.linalg.svd(oblique(i), full_matrices=False)
    gamma, X = U[:, :n] * np.sqrt(s[:n]), np.sqrt(s[:n])[:, None] * Vt[:n]
    X_next = np.linalg.pinv(gamma[:-p_out]) @ oblique(i + 1)
    theta = np.vstack([X_next, rows([i], range(m, q))]) @ np.linalg.pinv(np.vstack([X, rows([i], range(m))]))
    return theta[:n, :n], theta[:n, n:], theta[n:, :n], theta[n:, n:]


def test_subspace_recovers_an_exact_system_and_annihilates_its_data():
    system, w = system_data(2, 2, 3, 400, 0.0, seed=5)
    R, structure, p = subspace_of(w, 2, 3)
    H = structure.hankel(p)
    assert R.shape == (2, 16)
    # the kernel of the exact model annihilates exact data to rounding (relative to R and H)
    assert np.linalg.norm(R @ H) <= 1e-10 * np.linalg.norm(R) * np.linalg.norm(H)
    model = kernel_to_ss(normalize_kernel(R, 2, 3), 2, 3)
    assert np.allclose(markov_parameters(model, 10), markov_parameters(system, 10), atol=1e-8)


def test_subspace_equals_a_dense_reference_on_noisy_data():
    # the same algorithm on the dense matrices: equal to rounding, amplified by the conditioning
    _, w = system_data(1, 2, 2, 300, 0.1, seed=6)
    q, i = 3, 5
    structure = Structure.time_major(q, 2, [len(w) - 2])
    A, B, C, D = starts.subspace_model(structure.split(structure.params_from_series([w])), 1, 2, horizon=i)
    A_ref, B_ref, C_ref, D_ref = dense_n4sid(w, 1, 2, i)
    ours, reference = (markov_parameters(make(*abcd), 12) for abcd in ((A, B, C, D), (A_ref, B_ref, C_ref, D_ref)))
    assert np.allclose(np.sort_complex(np.linalg.eigvals(A)), np.sort_complex(np.linalg.eigvals(A_ref)), atol=1e-8)
    assert np.allclose(ours, reference, atol=1e-8 * np.abs(reference).max())


def make(A, B, C, D):
    from ident.representations import make_ss
    return make_ss(A, B, C, D)


def test_subspace_chunks_and_several_series_give_the_model_of_the_stacked_windows():
    system, w = system_data(1, 1, 2, 260, 0.0, seed=7)
    series = [w[:120], w[120:]]
    structure = Structure.time_major(2, 2, [118, 138])
    samples = structure.split(structure.params_from_series(series))
    whole = starts.subspace_model(samples, 1, 2, horizon=4)
    # the factor of the windows of both series, in small chunks, is the same factor (up to signs of rows)
    rows = [(v, lag) for lag in range(8) for v in range(2)]
    F = starts.window_triangular_factor(samples, rows, [113, 133], chunk=7)
    M = np.hstack([block_hankel(s, 8) for s in series])
    assert np.allclose(F.T @ F, M @ M.T, rtol=1e-12, atol=1e-12 * np.abs(M).max() ** 2)
    # exact data: the windows never cross from one series to the next, so the model is exact
    assert np.allclose(np.sort_complex(np.linalg.eigvals(whole[0])),
                       np.sort_complex(np.linalg.eigvals(system.A)), atol=1e-8)


def test_subspace_kernel_is_the_kernel_of_the_representations_chapter():
    rng = np.random.default_rng(8)
    system = random_system(2, 2, 2, rng)
    structure = Structure.time_major(4, 2, [50])
    ours = starts.model_kernel(*(np.asarray(x) for x in (system.A, system.B, system.C, system.D)), structure)
    theirs = ss_to_kernel(system, 2)
    # the same row space: each kernel's rows are combinations of the other's
    assert np.linalg.matrix_rank(np.vstack([ours, theirs]), tol=1e-9) == 2


def test_subspace_autonomous_and_static_models():
    rng = np.random.default_rng(9)
    system = random_system(0, 1, 2, rng)
    y = simulate(system, np.zeros((200, 0)), np.array([1.0, -0.5]))
    R, structure, p = subspace_of(y, 0, 2)
    H = structure.hankel(p)
    assert np.linalg.norm(R @ H) <= 1e-9 * np.linalg.norm(R) * np.linalg.norm(H)
    _, w = system_data(2, 1, 1, 80, 0.1, seed=10)
    static, structure0, p0 = subspace_of(w, 2, 0)
    assert np.array_equal(static, starts.least_squares(p0, structure0, 2))


def test_subspace_refuses_data_too_short_with_the_numbers():
    _, w = system_data(1, 1, 3, 14, 0.1, seed=11)
    with pytest.raises(ValueError, match="too short for the subspace start: windows of 8 samples"):
        subspace_of(w, 1, 3)


@pytest.mark.parametrize("noise", [0.0, 0.1])
def test_subspace_agrees_with_nfoursid(noise):
    # an independent implementation (nfoursid, a test-only dependency) on the same data and horizon:
    # on exact data the same model to rounding; on noisy data both estimate it, and they agree to a
    # fraction of the estimation error (nfoursid reads the next states off one shifted state sequence)
    import pandas as pd
    from nfoursid.nfoursid import NFourSID

    system, w = system_data(1, 2, 2, 2000, noise, seed=12)
    i = 6
    structure = Structure.time_major(3, 2, [len(w) - 2])
    A, B, C, D = starts.subspace_model(structure.split(structure.params_from_series([w])), 1, 2, horizon=i)
    frame = pd.DataFrame(w, columns=["u", "y1", "y2"])
    peer = NFourSID(frame, output_columns=["y1", "y2"], input_columns=["u"], num_block_rows=i)
    peer.subspace_identification()
    model, _ = peer.system_identification(rank=4)
    poles = np.sort_complex(np.linalg.eigvals(A))
    peer_poles = np.sort_complex(np.linalg.eigvals(model.a))
    true_poles = np.sort_complex(np.linalg.eigvals(system.A))
    ours = markov_parameters(make(A, B, C, D), 8)
    theirs = markov_parameters(make(model.a, model.b, model.c, model.d), 8)
    truth = markov_parameters(system, 8)
    if noise == 0:
        assert np.allclose(poles, true_poles, atol=1e-8) and np.allclose(peer_poles, true_poles, atol=1e-6)
        assert np.allclose(ours, theirs, atol=1e-6 * np.abs(truth).max())
    else:
        error = np.abs(ours - truth).max()
        assert np.abs(poles - true_poles).max() < 0.05 and np.abs(peer_poles - poles).max() < 0.01
        assert 0 < error < 0.02 * np.abs(truth).max()  # the noise shows, and both estimate the system
        assert np.abs(ours - theirs).max() <= 0.5 * error  # closer to each other than to the truth


# --- exact data: the null space to the data's accuracy ------------------------------------------

# The null vector of H_15 of the paper's chain data (reference/msd_uy.txt, columns u, y; rows time-major
# u(t), y(t), ..., u(t+14), y(t+14)), from the data's doubles in 300-bit arithmetic (mpmath: H H^T
# formed exactly, its eigenvector of the smallest eigenvalue), rounded to double.
CHAIN_NULL_VECTOR = np.array([
    1.4074242990463013e-09, 2.840696865754661e-05, 3.059269222895313e-09, -0.0004284163428218533,
    -1.7309829299452947e-07, 0.003204688414515046, 1.2247743295493073e-06, -0.015505217657204596,
    -4.212494819377223e-06, 0.053636006895897245, 7.41123723417739e-06, -0.1393223106774716,
    -2.13308654697634e-06, 0.278840670285609, -1.968315458562384e-05, -0.4352520151744242,
    4.492878857870173e-05, 0.531052014274103, -4.47491515887657e-05, -0.5029798589754396,
    1.7036916080456837e-05, 0.3634532526314955, 4.315656086689624e-06, -0.19404328936364326,
    -4.0913087983990635e-06, 0.07227524309706453, -1.5715955573077615e-07, -0.016794114052442206,
    2.4898775886035995e-16, 0.001834939676105505])


def chain_problem(ell: int):
    from conftest import PROJECT_ROOT
    path = PROJECT_ROOT / "reference" / "msd_uy.txt"
    if not path.is_file():
        pytest.skip(f"reference data not found at {path}")
    w = np.loadtxt(path)
    return Structure.time_major(2, ell, [len(w) - ell]), w.ravel(order="F"), 2 * (ell + 1) - 1


def distance_to(kernel, vector) -> float:
    unit = kernel.ravel() / np.linalg.norm(kernel)
    return min(np.linalg.norm(unit - vector), np.linalg.norm(unit + vector))


@pytest.mark.parametrize("chunk", [4096, 37])
def test_the_null_space_of_exact_data_to_their_accuracy(chunk) -> None:
    # sigma_29 of H_15 is 2e-15 sigma_1: the SVD's null vector may mix that direction in by up to
    # eps sigma_1 / sigma_29, a few percent (7.6e-5 .. 4.7e-4 here, by BLAS kernel); exact_kernel's
    # error is that of rounding the 300-bit vector (1e-15 under every kernel tried), asserted to 1e-10
    structure, p, rank = chain_problem(14)
    assert distance_to(starts.unstructured_lra(p, structure, rank), CHAIN_NULL_VECTOR) > 1e-6  # what it improves
    kernel = starts.exact_kernel(p, structure, rank, chunk=chunk)
    assert kernel.shape == (1, 30) and abs(np.linalg.norm(kernel) - 1) < 1e-14
    assert distance_to(kernel, CHAIN_NULL_VECTOR) < 1e-10


def test_no_kernel_where_the_null_space_of_exact_data_is_not_unique() -> None:
    structure, p, rank = chain_problem(15)  # lag 15 for data of lag 14: a null space of dimension 2
    assert starts.exact_kernel(p, structure, rank) is None


def test_the_null_space_of_exact_data_with_several_outputs_and_series() -> None:
    # two outputs (g = 2), two series of different lengths: orthonormal rows that annihilate the data
    # to rounding (the layout of the g = 2, several-series path; the accuracy is the chain's test above)
    from ident.representations import random_system, simulate
    rng = np.random.default_rng(4)
    system = random_system(1, 2, 2, rng, radius=(0.05, 0.3))
    series = [np.hstack([u, simulate(system, u, rng.standard_normal(system.nstates))])
              for u in (rng.standard_normal((200, 1)), rng.standard_normal((150, 1)))]
    from ident.structure import series_to_parameters
    structure = Structure.time_major(3, 2, [len(w) - 2 for w in series])
    p, rank = series_to_parameters(series), 3 * 3 - 2
    kernel = starts.exact_kernel(p, structure, rank)
    assert kernel.shape == (2, 9) and np.allclose(kernel @ kernel.T, np.eye(2), atol=1e-14)
    samples = structure.split(p)
    hankel = np.hstack([np.array([samples[j][i][lag: lag + n] for i, lag in starts.hankel_rows(structure)])
                        for j, n in enumerate(structure.n_cols)])  # Phi H(p)
    assert np.linalg.norm(kernel @ hankel) < 1e-13 * np.linalg.norm(hankel)
