"""Scaling of the solver with the number of samples T. Not a test: it prints a table.

Data: a random stable system with 2 inputs and 2 outputs of order 4 (q = 4, lag 2, rank
3 * 4 - 2 = 10, 20 parameters), an exact trajectory plus noise of standard deviation 0.1 on all
variables. Per T: iterations, cost evaluations, solver seconds, seconds per iteration (solver time /
iterations, start-up and rejected trials included), the time of one Gauss-Newton matrix ("jac") and
of one cost evaluation at the solution (band, Cholesky, two solves, the adjoint), the tracemalloc
peak of the solver call and the process's peak resident memory. Each T runs in its own process, so
that the peak memory is per T; the tracemalloc peak slows the solver itself down (by about 2.5x at
T = 1e6), so the solver time is measured again with tracemalloc off.

Usage: python benchmarks/bench_scaling.py [T ...] [--maxiter=N]
"""
import resource
import subprocess
import sys
import time
import tracemalloc
import warnings

import numpy as np

from ident.solver import SLRAWarning, slra
from ident.solver.cost import Problem
from ident.solver.optimiser import Chart
from ident.structure import Structure


def data(n_samples, seed=0):
    """Trajectory of a random stable 2 x 2 system of order 4, plus noise 0.1."""
    rng = np.random.default_rng(seed)
    n, m, p = 4, 2, 2
    A = rng.standard_normal((n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    B, C, D = (rng.standard_normal(s) for s in ((n, m), (p, n), (p, m)))
    u = rng.standard_normal((n_samples, m))
    x = rng.standard_normal(n)
    states = np.empty((n_samples, n))
    for t in range(n_samples):
        states[t] = x
        x = A @ x + B @ u[t]
    w = np.hstack([u, states @ C.T + u @ D.T])
    return w + 0.1 * rng.standard_normal(w.shape)


def one(n_samples, maxiter):
    """Measure one T and print its row."""
    structure = Structure.time_major(4, 2, [n_samples - 2])
    p = structure.params_from_series([data(n_samples)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SLRAWarning)
        tracemalloc.start()
        slra(p, structure, 10, maxiter=maxiter)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        result = slra(p, structure, 10, maxiter=maxiter)
    problem = Problem(p, structure)
    chart = Chart.from_kernel(result.R)
    started = time.perf_counter()
    state = problem.evaluate(result.R)
    seconds_cost = time.perf_counter() - started
    started = time.perf_counter()
    problem.normal_equations(state, chart.free_columns)
    seconds_jacobian = time.perf_counter() - started
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024 ** 2  # GB (ru_maxrss is in kB)
    print(f"{n_samples:>9d} {result.iterations:5d} {result.nfev:5d} {result.time:9.2f} "
          f"{result.time / max(result.iterations, 1):9.3f} {seconds_jacobian:9.3f} {seconds_cost:9.3f} "
          f"{peak / 1e9:9.3f} {rss:8.3f}  {result.misfit / (n_samples * 4):.4g}  {result.converged}", flush=True)


def main(argv):
    options = dict(a.lstrip("-").partition("=")[::2] for a in argv if a.startswith("--"))
    maxiter = int(options.get("maxiter", 100))
    sizes = [int(float(a)) for a in argv if not a.startswith("--")]
    if len(sizes) == 1:
        one(sizes[0], maxiter)
        return
    sizes = sizes or [1000, 10_000, 100_000, 1_000_000]
    print(f"maxiter={maxiter}")
    print(f"{'T':>9s} {'iter':>5s} {'nfev':>5s} {'solver s':>9s} {'s/iter':>9s} {'s/jac':>9s} "
          f"{'s/cost':>9s} {'peak GB':>9s} {'RSS GB':>8s}  M/(Tq)  conv", flush=True)
    for n_samples in sizes:
        subprocess.run([sys.executable, __file__, str(n_samples), f"--maxiter={maxiter}"], check=True)


if __name__ == "__main__":
    main(sys.argv[1:])
