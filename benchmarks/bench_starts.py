"""Time and memory of the initial approximations (ident.starts) against the number of samples T.
Not a test: it prints a table.

Data: those of benchmarks/bench_scaling.py (a random stable system with 2 inputs and 2 outputs of
order 4, lag 2, noise 0.1 on all variables). Per T and start ("lra", "arx", "subspace"): the
seconds of the start, the tracemalloc peak of the call (the arrays it allocates; the data p, T q
doubles, are allocated before) against the size of the data, and the poles' distance from the true
system's. Each T runs in its own process, so that the peak resident memory is per T. The subspace
start works on the triangular factor of a block-Hankel matrix with 2 i q rows (i = 15 here: 120
rows), accumulated over chunks of 4096 columns: its memory does not grow with T beyond the data.

Usage: python benchmarks/bench_starts.py [T ...]
"""
import resource
import subprocess
import sys
import time
import tracemalloc

import numpy as np

from ident import starts
from ident.solver.threads import one_blas_thread
from ident.structure import Structure

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
from bench_scaling import data  # noqa: E402  the same system and noise


def poles_of(kernel, structure):
    """Poles of the model of a kernel: the roots of det(Q(z)) (the y-part at each lag), ell = 2, p = 2."""
    from ident.representations import kernel_to_ss, normalize_kernel
    return np.sort_complex(np.linalg.eigvals(kernel_to_ss(normalize_kernel(kernel, 2, 2), 2, 2).A))


def true_poles(seed=0):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((4, 4))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    return np.sort_complex(np.linalg.eigvals(A))


def one(n_samples):
    structure = Structure.time_major(4, 2, [n_samples - 2])
    p = structure.params_from_series([data(n_samples)])
    truth = true_poles()
    for name in ("lra", "arx", "subspace"):
        with one_blas_thread():  # as ident computes them: BLAS on one thread, as in the solver
            starts.start(name, p, structure, 10)  # warm up (imports, BLAS); the time is that of the second
            tracemalloc.start()
            started = time.perf_counter()
            kernel = starts.start(name, p, structure, 10)
            seconds = time.perf_counter() - started
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        distance = np.abs(poles_of(kernel, structure) - truth).max()
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024 ** 2  # GB (ru_maxrss is in kB)
        print(f"{n_samples:>9d} {name:>9s} {seconds:9.2f} {peak / 1e6:10.1f} {p.nbytes / 1e6:10.1f} "
              f"{rss:8.3f} {distance:12.2e}", flush=True)


def main(argv):
    sizes = [int(float(a)) for a in argv]
    if len(sizes) == 1:
        one(sizes[0])
        return
    sizes = sizes or [1000, 10_000, 100_000, 1_000_000]
    print(f"{'T':>9s} {'start':>9s} {'seconds':>9s} {'peak MB':>10s} {'data MB':>10s} {'RSS GB':>8s} "
          f"{'pole error':>12s}", flush=True)
    for n_samples in sizes:
        subprocess.run([sys.executable, __file__, str(n_samples)], check=True)


if __name__ == "__main__":
    main(sys.argv[1:])
