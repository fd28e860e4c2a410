"""The contract of the solver's fast path (ident.solver.fast, with the factor's stationary
shortcut): on a bed of problems, its cost, J^T J, J^T e and half Hessian equal those of the plain
algorithm (ident.solver.reference) to 1e-12 of their size, or to the rounding that the conditioning of
Gamma allows where that is larger.

The bed holds the problems on which each of the fast path's devices acts: the delayed bases (long
series, constant weights), the delayed products of a batch in the solver's layout (many short series
of one length), the bases of whole stationary blocks made from their sources (small chunks), the
free responses (a switch before they decay), weights that vary in time (no shortcut), exact
variables, depths 1 to 4, tiny series and a nearly singular Gamma.
"""
import ast
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from ident.solver.cost import Problem
from ident.solver.optimiser import Chart
from ident.solver.reference import _banded_cholesky, gauss_newton_reference, hankel_operator
from ident.starts import unstructured_lra as initial_kernel
from ident.structure import Structure
from test_solver import general_structure, grouped_structure, simulate

EPS = np.finfo(float).eps


# ------------------------------------------------------------------------------------------ the bed
def small(make, weights):
    """A small general structure (unequal depths, a permutation, random and inf weights) at a random kernel."""
    def problem():
        structure, rng = make(weights=weights)
        return rng.standard_normal(structure.n_params), structure, rng.standard_normal((3, structure.n_rows)), {}
    return problem


def tiny(n_cols):
    """Two series of n_cols and n_cols + 1 columns, depth 3: fewer columns than the band is wide."""
    def problem():
        rng = np.random.default_rng(20 + n_cols)
        structure = Structure.time_major(2, 2, [n_cols, n_cols + 1])
        return rng.standard_normal(structure.n_params), structure, rng.standard_normal((2, 6)), {}
    return problem


def static():
    """Depth 1 (lag 0): Gamma block-diagonal; 500 samples, one exact variable."""
    rng = np.random.default_rng(4)
    structure = Structure.time_major(3, 0, [500])
    weights = np.ones(structure.n_params)
    structure.split(weights)[0][2][:] = np.inf
    structure = Structure(structure.depths, structure.n_cols, structure.perm, weights)
    p = rng.standard_normal(structure.n_params)
    return p, structure, initial_kernel(p, structure, 2), {}


def delayed_bases():
    """Two long series (2998 and 1500 columns), constant weights, variable 3 exact: the delayed bases."""
    rng = np.random.default_rng(7)
    w = simulate(rng, 2, 2, 4, 3000)
    structure = Structure.time_major(4, 2, [2998, 1500])
    weights = np.ones(structure.n_params)
    for samples_j in structure.split(weights):
        samples_j[3][:] = np.inf
    structure = Structure(structure.depths, structure.n_cols, structure.perm, weights)
    p = structure.params_from_series([w, w[:1502] + 0.1 * rng.standard_normal((1502, 4))])
    return p, structure, initial_kernel(p, structure, 10), {}


def batch_of_series():
    """40 series of 600 samples: solved a batch at a time, delayed products in the solver's layout."""
    rng = np.random.default_rng(5)
    n_series, n_samples = 40, 600
    w = simulate(rng, 2, 2, 4, n_series * n_samples)
    series = [w[k * n_samples: (k + 1) * n_samples] + 0.1 * rng.standard_normal((n_samples, 4))
              for k in range(n_series)]
    structure = Structure.time_major(4, 2, [n_samples - 2] * n_series)
    p = structure.params_from_series(series)
    return p, structure, initial_kernel(p, structure, 10), {}


def stationary_blocks(n_series, n_samples):
    """Unequal depths, constant weights 2 and 0.5 and an exact variable, chunks of 256 columns: whole
    stationary blocks whose bases are made from their sources."""
    def problem():
        rng = np.random.default_rng(12)
        shape = Structure((3, 2, 3), (n_samples,) * n_series, perm=tuple(rng.permutation(8)))
        weights = np.concatenate([np.full(shape.n_samples(j, i), weight) for j in range(n_series)
                                  for i, weight in enumerate((2.0, np.inf, 0.5))])
        structure = Structure(shape.depths, shape.n_cols, shape.perm, weights)
        series = [simulate(rng, 1, 2, 2, n_samples + 2) + 0.1 * rng.standard_normal((n_samples + 2, 3))
                  for _ in range(n_series)]
        p = np.concatenate([w[: structure.n_samples(j, i), i] for j, w in enumerate(series) for i in range(3)])
        return p, structure, initial_kernel(p, structure, 6), {"chunk_elements": 1 << 12}
    return problem


def depth_one_weighted():
    """The weighted variables of depth 1, the deep one (depth 3) exact, 3000 columns, small chunks."""
    rng = np.random.default_rng(3)
    shape = Structure((1, 1, 3), (3000,), perm=tuple(range(5)))
    weights = np.concatenate([np.full(shape.n_samples(0, i), w) for i, w in enumerate((1.0, 2.0, np.inf))])
    structure = Structure(shape.depths, shape.n_cols, shape.perm, weights)
    p = rng.standard_normal(structure.n_params)
    return p, structure, initial_kernel(p, structure, 3), {"chunk_elements": 1 << 12}


def free_responses(n_series, n_samples):
    """Depth 4, a perturbed kernel: the switch to the delayed bases comes before the free responses decay."""
    def problem():
        rng = np.random.default_rng(11)
        series = [simulate(rng, 2, 2, 6, n_samples) for _ in range(n_series)]
        structure = Structure.time_major(4, 3, [n_samples - 3] * n_series)
        p = structure.params_from_series(series)
        R = initial_kernel(p, structure, 14)
        return p, structure, R + 0.3 * rng.standard_normal(R.shape), {}
    return problem


def varying_weights():
    """One series of 2000 samples with weights that vary in time: no shortcut, every row solved."""
    rng = np.random.default_rng(9)
    structure = Structure.time_major(3, 2, [1998])
    weights = np.exp(0.5 * rng.standard_normal(structure.n_params))
    structure = Structure(structure.depths, structure.n_cols, structure.perm, weights)
    p = structure.params_from_series([simulate(rng, 1, 2, 3, 2000) + 0.1 * rng.standard_normal((2000, 3))])
    return p, structure, initial_kernel(p, structure, 7), {}


def ill_conditioned():
    """Two nearly dependent kernel rows, 6000 samples of 8 variables: kappa(Gamma) above 1e3, the factor
    stationary to its rounding level."""
    rng = np.random.default_rng(7)
    n_samples, q = 6000, 8
    structure = Structure.time_major(q, 1, [n_samples - 1])
    p = structure.params_from_series([rng.standard_normal((n_samples, q))])
    R = rng.standard_normal((4, 2 * q))
    R[3] = R[2] + 0.01 * rng.standard_normal(2 * q)
    return p, structure, R, {}


BED = {
    "general, weights": small(general_structure, True),
    "general, no weights": small(general_structure, False),
    "grouped, weights": small(grouped_structure, True),
    "grouped, no weights": small(grouped_structure, False),
    "tiny, 1 column": tiny(1),
    "tiny, 4 columns": tiny(4),
    "depth 1": static,
    "delayed bases": delayed_bases,
    "batch of 40 series": batch_of_series,
    "stationary blocks, 1 series": stationary_blocks(1, 3000),
    "stationary blocks, 6 series": stationary_blocks(6, 1500),
    "weighted variables of depth 1": depth_one_weighted,
    "free responses, 1 series": free_responses(1, 3000),
    "free responses, 3 series": free_responses(3, 1000),
    "weights varying in time": varying_weights,
    "ill-conditioned": ill_conditioned,
}


def gamma_conditioning(structure, R) -> float:
    """kappa(Gamma) of the worst series: its largest eigenvalue and that of Gamma^{-1} by Lanczos (a
    few products with the sparse Gamma and solves with its banded factor), dense below 400 rows."""
    variable_major = np.empty_like(R)
    variable_major[:, list(structure.perm)] = R
    worst = 1.0
    for n_cols, v_j in zip(structure.n_cols, structure.split(structure.inverse_weights)):
        G = hankel_operator(variable_major, structure.depths, n_cols)
        gamma = (G @ scipy.sparse.diags(np.concatenate(v_j)) @ G.T).tocsr()
        if gamma.shape[0] < 400:
            eigenvalues = np.linalg.eigvalsh(gamma.toarray())
            worst = max(worst, eigenvalues[-1] / eigenvalues[0])
            continue
        factor = _banded_cholesky(gamma, R.shape[0] * structure.max_depth - 1)
        inverse = scipy.sparse.linalg.LinearOperator(
            gamma.shape, matvec=lambda x: scipy.linalg.cho_solve_banded((factor, True), x), dtype=float)
        largest, inverse_largest = (scipy.sparse.linalg.eigsh(operator, 1, which="LA", tol=1e-3,
                                                              return_eigenvectors=False)[0]
                                    for operator in (gamma, inverse))
        worst = max(worst, largest * inverse_largest)
    return worst


# ------------------------------------------------------------------------------------ the contract
@pytest.mark.parametrize("name", list(BED))
def test_fast_path_equals_the_plain_algorithm(name):
    p, structure, R, options = BED[name]()
    free = Chart.from_kernel(R).free_columns
    problem = Problem(p, structure, **options)
    state = problem.evaluate(R)
    jtj, half_gradient, half_hessian = problem.normal_equations(state, free)
    reference = gauss_newton_reference(p, structure, R, free)
    # the fast path's errors (the shortcut takes the factor as stationary at its rounding level, and
    # J^T J and the Hessian are differences of larger Gram matrices) grow with kappa(Gamma): at most
    # 30 kappa eps on this bed; 1e-12 holds wherever kappa eps is below 1e-14
    tolerance = max(1e-12, 100 * gamma_conditioning(structure, R) * EPS)
    errors = {"cost": abs(state.cost - reference.cost) / reference.cost}
    for what, fast, plain in zip(("J^T J", "J^T e", "Hessian"), (jtj, half_gradient, half_hessian), reference[1:]):
        errors[what] = np.abs(fast - plain).max() / np.abs(plain).max()
    assert max(errors.values()) <= tolerance, f"{errors} above {tolerance:.1e}"


def test_the_fast_path_is_reached_through_one_dispatch_point():
    # the plain solver imports ident.solver.fast in one place only (Problem.normal_equations's module),
    # and the fast path imports none of the modules that reach it
    solver = Path(__file__).resolve().parents[1] / "src" / "ident" / "solver"
    importers = set()
    for path in solver.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([node.module or ""] + [f"{node.module}.{alias.name}" for alias in node.names]
                     if isinstance(node, ast.ImportFrom) else
                     [alias.name for alias in node.names] if isinstance(node, ast.Import) else [])
            module = ".".join(path.relative_to(solver.parent).with_suffix("").parts)
            if any(name == "ident.solver.fast" or name.startswith("ident.solver.fast.") for name in names):
                importers.add(module)
            if "fast" in path.parts:
                assert not any(name in ("ident.solver.cost", "ident.solver") or name.startswith("ident.solver.cost")
                               for name in names), f"{module} imports back what reaches it: {names}"
    assert {m for m in importers if not m.startswith("solver.fast")} == {"solver.cost"}
