"""literate_tools.tangled.examples (the examples' helpers) beyond what the examples of 03-examples.md show:
parameter checks and edge cases."""
from __future__ import annotations

import control
import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ident.hankel import block_hankel  # noqa: E402
from literate_tools.tangled import examples  # noqa: E402


# --- the mass-spring-damper chain ---------------------------------------------------------------

def test_chain_defaults_scale_with_n():
    chain = examples.mass_spring_damper_chain(4)
    assert chain.nstates == 9 and chain.ninputs == 1 and chain.noutputs == 1
    assert np.array_equal(chain.C[0], np.eye(9)[1])  # the middle mass (index (4 - 1) // 2 = 1)
    assert np.array_equal(chain.B[:, 0], np.eye(9)[4])  # velocity of mass 0
    masses = np.array([4.0, 3.0, 2.0, 1.0])
    assert np.allclose(chain.A[4:8, 4:8].diagonal(), -(np.array([1, 2, 2, 1]) + 0.05) / masses)


def test_chain_one_column_of_B_per_input_one_row_of_C_per_output():
    chain = examples.mass_spring_damper_chain(5, inputs=[0, 4], outputs=[1, 2, 3])
    assert chain.B.shape == (11, 2) and chain.C.shape == (3, 11) and chain.D.shape == (3, 2)
    assert np.array_equal(chain.B[[5, 9]], np.eye(2)) and chain.B.sum() == 2
    assert np.array_equal(chain.C[:, [1, 2, 3]], np.eye(3)) and chain.C.sum() == 3


@pytest.mark.parametrize("springs", [None, [2.0, 1.0, 3.0, 0.5, 1.5]])
def test_chain_rest_configuration_is_an_equilibrium_with_walls(springs):
    """With springs to both walls (at 0 and (N + 1) delta) the rest positions i delta still balance."""
    n_masses, delta = 4, 0.7
    chain = examples.mass_spring_damper_chain(n_masses, springs=springs, dampers=[1, 1, 1, 1, 1],
                                              spring_length=delta)
    rest = np.r_[delta * np.arange(1, n_masses + 1), np.zeros(n_masses), 1.0]
    assert np.allclose(chain.A @ rest, 0, atol=1e-14)


def test_chain_with_walls_has_no_rigid_body_mode():
    chain = examples.mass_spring_damper_chain(3, springs=[1, 1, 1, 1], dampers=[1, 1, 1, 1])
    eigenvalues = np.linalg.eigvals(chain.A)
    assert np.sum(np.abs(eigenvalues) < 1e-12) == 1  # only the constant state
    assert np.linalg.matrix_rank(control.ctrb(chain.A, chain.B)) == 6


@pytest.mark.parametrize("kwargs, error, words", [
    (dict(n_masses=0), ValueError, "n_masses"),
    (dict(n_masses=2.5), TypeError, "n_masses"),
    (dict(n_masses=True), TypeError, "n_masses"),
    (dict(masses=[1, 2]), ValueError, "masses must be 7 entries"),
    (dict(masses=[1, 1, 1, 0, 1, 1, 1]), ValueError, "masses must be positive"),
    (dict(springs=np.ones(7)), ValueError, "springs must be 8 entries"),
    (dict(springs=[0, 1, 1, -1, 1, 1, 1, 0]), ValueError, "springs must be non-negative"),
    (dict(dampers=[0, 1, 1, np.nan, 1, 1, 1, 0]), ValueError, "dampers must be finite"),
    (dict(dampers="abc"), TypeError, "dampers"),
    (dict(friction=-0.1), ValueError, "friction must be non-negative"),
    (dict(friction=[0.1, 0.2]), ValueError, "friction must be a single number"),
    (dict(spring_length=np.inf), ValueError, "spring_length must be finite"),
    (dict(inputs=[7]), ValueError, "inputs must be 0-based mass indices in 0 .. 6"),
    (dict(inputs=[-1]), ValueError, "inputs"),
    (dict(inputs=[]), TypeError, "inputs must be a non-empty"),
    (dict(inputs=[0.0]), TypeError, "inputs"),
    (dict(outputs=[2, 2]), ValueError, "outputs lists a mass more than once"),
    (dict(outputs="3"), TypeError, "outputs"),
])
def test_chain_parameter_errors_name_the_argument(kwargs, error, words):
    with pytest.raises(error, match=words):
        examples.mass_spring_damper_chain(**kwargs)


# --- eigenvalue matching ------------------------------------------------------------------------

def test_match_eigenvalues_pairs_by_total_distance():
    reference = np.array([1.0, 0.5 + 0.5j, 0.5 - 0.5j, 0.0])
    found = np.array([0.51 - 0.5j, 0.02, 0.5 + 0.49j])
    match = examples.match_eigenvalues(found, reference)
    assert list(match.partner) == [2, 3, 1]
    assert np.allclose(match.errors, [0.01, 0.02, 0.01])
    assert np.array_equal(match.unmatched, [1.0])


def test_match_eigenvalues_needs_enough_reference_values():
    with pytest.raises(ValueError, match="len\\(found\\) <= len\\(reference\\)"):
        examples.match_eigenvalues([1, 2, 3], [1, 2])


# --- kernel of permuted variables ---------------------------------------------------------------

def test_permute_kernel_annihilates_the_permuted_hankel_matrix():
    rng = np.random.default_rng(0)
    q, ell = 3, 2
    w = rng.standard_normal((20, q))
    R = rng.standard_normal((2, (ell + 1) * q))
    perm = [2, 0, 1]
    permuted = examples.permute_kernel(R, perm)
    assert np.allclose(permuted @ block_hankel(w[:, perm], ell + 1), R @ block_hankel(w, ell + 1))
    inverse = np.argsort(perm)
    assert np.array_equal(examples.permute_kernel(permuted, inverse), R)


@pytest.mark.parametrize("R, perm, words", [
    (np.ones((1, 6)), [0, 0, 1], "permutation"),
    (np.ones((1, 7)), [0, 1, 2], "blocks of q = 3"),
    (np.ones(6), [0, 1, 2], "2-D"),
])
def test_permute_kernel_errors(R, perm, words):
    with pytest.raises(ValueError, match=words):
        examples.permute_kernel(R, perm)


# --- step-response data -------------------------------------------------------------------------

def test_step_response_data_layout():
    responses = np.arange(4 * 2 * 3, dtype=float).reshape(4, 2, 3)
    w = examples.step_response_data(responses)
    assert w.shape == (4, 5, 3)
    for k in range(3):
        assert np.array_equal(w[:, :3, k], np.tile(np.eye(3)[k], (4, 1)))
        assert np.array_equal(w[:, 3:, k], responses[:, :, k])


def test_step_response_data_needs_a_3d_array():
    with pytest.raises(ValueError, match="T x p x m"):
        examples.step_response_data(np.ones((4, 2)))


# --- shared data and figures --------------------------------------------------------------------

def test_shared_path_is_none_when_absent_and_checks_its_arguments():
    assert examples.shared_path("reference", "no-such-file.json") is None
    with pytest.raises(TypeError, match="parts"):
        examples.shared_path()
    with pytest.raises(TypeError, match="parts"):
        examples.shared_path("reference", 3)


def test_save_figure_writes_only_when_asked(tmp_path, monkeypatch):
    monkeypatch.delenv("IDENT_FIGURES", raising=False)
    figure, axis = plt.subplots()
    axis.plot([0, 1], [1, 0])
    assert examples.save_figure(figure, "quiet") is None
    assert not plt.fignum_exists(figure.number)

    monkeypatch.setenv("IDENT_FIGURES", str(tmp_path / "figures"))
    figure, axis = plt.subplots()
    examples.plot_fit(axis, np.arange(5.0), np.arange(5.0) + 0.1, true=np.arange(5.0), title="t", ylabel="y")
    path = examples.save_figure(figure, "written")
    assert path == tmp_path / "figures" / "written.png" and path.stat().st_size > 1000
    assert not plt.fignum_exists(figure.number)


@pytest.mark.parametrize("name", ["", "a/b", "x.png", None])
def test_save_figure_refuses_bad_names(name):
    figure = plt.figure()
    try:
        with pytest.raises(ValueError, match="name"):
            examples.save_figure(figure, name)
    finally:
        plt.close(figure)
