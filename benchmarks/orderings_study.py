"""Does the computed misfit depend on the ordering of the variables? ident for every ordering on 544 data sets.

The study of "Where the orderings differ" in literate/03-examples.md: for each data set (a random
system of the class (m, p, ell), a trajectory of T samples from a random initial state, noise on
every variable, seeded like the chunk's two_by_two_data), ident(w[:, perm], m, ell, init="lra") (the
paper's start, as the chapter's examples) for every permutation perm of the q = m + p variables. Prints on how many data sets the
misfits of all orderings agree to 1e-6, 1e-9 and 1e-12 relative, the largest spreads, and for every
data set that disagrees beyond 1e-9 whether a restart from the worst ordering's kernel reaches the
best misfit (a stall) or not. Not a test: about 5 minutes on one core.

Usage: OPENBLAS_NUM_THREADS=1 python benchmarks/orderings_study.py
"""
import itertools
import time
import warnings

import numpy as np

from ident import ident
from ident.representations import random_system, simulate

BLOCKS = [  # (model classes (m, p, ell), T, noise, seeds)
    ([(2, 2, 2), (1, 1, 3), (1, 2, 2), (2, 1, 3)], [30, 100], [0.1, 0.5, 1.0], range(0, 8)),
    ([(2, 2, 2), (2, 2, 3), (1, 2, 2), (2, 1, 2)], [30, 100], [0.5, 1.0], range(8, 30)),
]


def noisy_trajectory(m, p, ell, seed, noise, n_samples):
    """The data of one data set; for (2, 2, 2) the same as two_by_two_data(seed, noise, T)."""
    rng = np.random.default_rng(seed)
    system = random_system(m, p, ell, rng)
    u = rng.standard_normal((n_samples, m))
    w0 = np.hstack([u, simulate(system, u, rng.standard_normal(ell * p))])
    return w0 + noise * rng.standard_normal(w0.shape)


def quiet_ident(*args, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ident(*args, **options)


def main():
    start = time.perf_counter()
    spreads, not_converged, n_orderings = [], 0, 0
    for classes, lengths, noises, seeds in BLOCKS:
        for (m, p, ell), n_samples, noise, seed in itertools.product(classes, lengths, noises, seeds):
            w = noisy_trajectory(m, p, ell, seed, noise, n_samples)
            runs = [(perm, quiet_ident(w[:, list(perm)], m, ell, init="lra")[1])
                    for perm in itertools.permutations(range(m + p))]
            n_orderings += len(runs)
            not_converged += sum(not info.converged for _, info in runs)
            misfits = np.array([info.M for _, info in runs])
            spread = (misfits.max() - misfits.min()) / misfits.min()
            spreads.append((spread, (m, p, ell), n_samples, noise, seed))
            if spread > 1e-9:
                perm, worst = runs[int(np.argmax(misfits))]
                restarted = quiet_ident(w[:, list(perm)], m, ell, sys0=worst.Rh)[1]
                kind = "stall" if restarted.M <= misfits.min() * (1 + 1e-6) else "not a stall"
                print(f"({m}, {p}, {ell}) T={n_samples} noise={noise} seed={seed}: spread {spread:.1e}, "
                      f"restart from the worst: {restarted.M:.6f} against the best {misfits.min():.6f} ({kind})")
    values = np.array([s[0] for s in spreads])
    print(f"{len(spreads)} data sets, {n_orderings} orderings, {not_converged} not converged, "
          f"{time.perf_counter() - start:.0f} s")
    for tol in (1e-6, 1e-9, 1e-12):
        print(f"all orderings agree to {tol:g} relative: {np.sum(values <= tol)} data sets")
    print("largest spreads:", ", ".join(f"{s:.1e} {c} T={t} noise={n} seed={k}"
                                        for s, c, t, n, k in sorted(spreads, reverse=True)[:3]))


if __name__ == "__main__":
    main()
