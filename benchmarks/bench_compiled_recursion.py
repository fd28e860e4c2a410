"""Would a compiled solve pay? The Gauss-Newton matrix's forward solves at T = 1e6 against a compiled
recursion, side by side in one process. Not a test, and numba is not a dependency of ident: this
script runs only where numba is installed (`pip install numba` in a scratch environment).

The case is side_by_side.py's scale:1e6 (the 2 x 2 system of order 4, lag 2, g = 2): the factor at
the solver's solution is stationary past a short prefix, and a Gauss-Newton matrix solves its
n_base = 16 bases over the series chunk by chunk (2^18 numbers per chunk, as the solver's
chunk_elements). Timed, best of --repeats:

    chunked     ident's ForwardSolver over the chunks of the solver's own layout (rows per right-hand
                side; block-wise BLAS-3 on the stationary rows), as in a Gauss-Newton matrix
    compiled    the stationary recursion x_t = L_0^{-1} (b_t - sum_k L_k x_{t-k}) compiled by numba,
                time-major with the right-hand sides innermost (vectorised), over the whole series,
                the transposing copies into and out of that layout included
    recursion   the compiled recursion alone, on time-major copies made before the clock starts
    lapack      dtbtrs column by column over the whole series (ident's fallback)

and the largest difference of the compiled solution from the chunked one past the factor's first
1000 stationary rows, relative to the largest entry there (the recursion uses the stationary block row
from row 0, the factor its own prefix; the difference decays within the prefix's reach).

Usage: python benchmarks/bench_compiled_recursion.py [--repeats=3] [--samples=1000000]
"""
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import side_by_side  # noqa: E402  the scale case's data

from ident.solver import SLRAWarning, slra  # noqa: E402
from ident.solver.blocked import banded_solve, dense_factor  # noqa: E402
from ident.solver.cost import Problem  # noqa: E402
from ident.structure import Structure  # noqa: E402


def compiled_recursion():
    """The time-major stationary recursion compiled by numba (None where numba is missing)."""
    try:
        import numba
    except ImportError:
        return None

    @numba.njit(cache=False)
    def recursion(blocks, b):  # blocks (s + 1, g, g): L_0 (lower triangular), L_1 .. L_s; b (n, g, R) in place
        n, g, n_rhs = b.shape
        for t in range(n):
            for i in range(g):
                row = b[t, i]
                for k in range(1, blocks.shape[0]):
                    if t >= k:
                        for j in range(g):
                            coefficient, earlier = blocks[k, i, j], b[t - k, j]
                            for r in range(n_rhs):
                                row[r] -= coefficient * earlier[r]
                for j in range(i):
                    coefficient, earlier = blocks[0, i, j], b[t, j]
                    for r in range(n_rhs):
                        row[r] -= coefficient * earlier[r]
                for r in range(n_rhs):
                    row[r] /= blocks[0, i, i]
        return b

    return recursion


def main(repeats=3, n_samples=10 ** 6, n_rhs=16, chunk_elements=1 << 18):
    recursion = compiled_recursion()
    if recursion is None:
        print("numba is not installed: nothing to compare (pip install numba in a scratch environment)")
        return
    w = side_by_side.system_data(n_samples)
    structure = Structure.time_major(4, 2, [len(w) - 2])
    p = structure.params_from_series([w])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SLRAWarning)
        kernel = slra(p, structure, 10, maxiter=3).R
    factor = Problem(p, structure).evaluate(kernel).factors[0]
    g = factor.n_eqs
    s = factor.band.shape[0] // g - 1
    first = factor.forward_part().first_row  # a stationary block row: L_s .. L_1, L_0
    row = dense_factor(factor.band, first, g, first - s * g, (s + 1) * g)
    blocks = np.stack([row[:, (s - k) * g: (s - k + 1) * g] for k in range(s + 1)])
    rhs = np.random.default_rng(0).standard_normal((n_rhs, factor.band.shape[1]))  # the solver's layout
    recursion(blocks, np.ascontiguousarray(rhs[:, : 10 * g].T).reshape(-1, g, n_rhs))  # compiled before timing

    def chunked():
        solver, n_cols, start = factor.forward_solver(), factor.band.shape[1] // g, 0
        out = np.empty_like(rhs)
        rows = max(256, chunk_elements // (n_rhs * g))
        while start < n_cols:
            stop = solver.block_end(min(n_cols, start + rows) * g) // g if start + rows < n_cols else n_cols
            out[:, start * g: stop * g] = solver.solve(np.ascontiguousarray(rhs[:, start * g: stop * g]))
            start = stop
        return out

    def compiled():
        return recursion(blocks, np.ascontiguousarray(rhs.T).reshape(-1, g, n_rhs)).reshape(-1, n_rhs).T

    time_major = [np.ascontiguousarray(rhs.T).reshape(-1, g, n_rhs) for _ in range(repeats)]  # one per call

    def recursion_alone():
        return recursion(blocks, time_major.pop()).reshape(-1, n_rhs).T

    def lapack():
        return banded_solve(factor.band, rhs.T.copy(order="F"), overwrite=True)  # rhs itself stays

    factor.fill_rows(0, factor.band.shape[1])  # the whole band, for dtbtrs
    best, results = {}, {}
    for _ in range(repeats):
        for name, method in (("chunked", chunked), ("compiled", compiled), ("recursion", recursion_alone),
                             ("lapack", lapack)):
            started = time.perf_counter()
            results[name] = method()
            best[name] = min(best.get(name, np.inf), time.perf_counter() - started)
    past = first + 1000 * g  # rows past the prefix's reach
    reference = results["chunked"][:, past:]
    print(f"T = {n_samples}, {n_rhs} right-hand sides, g = {g}, s = {s} (best of {repeats}, seconds):")
    for name, seconds in best.items():
        print(f"  {name:9s} {seconds:.4f}  ({seconds / best['chunked']:.2f} of chunked)")
    for name in ("compiled", "recursion", "lapack"):
        solution = (results[name].T if name == "lapack" else results[name])[:, past:]
        print(f"  {name} against chunked past row {past}: "
              f"{np.abs(solution - reference).max() / np.abs(reference).max():.1e}")


if __name__ == "__main__":
    options = dict(arg[2:].split("=") for arg in sys.argv[1:] if arg.startswith("--"))
    main(int(options.get("repeats", 3)), int(float(options.get("samples", 1e6))))
