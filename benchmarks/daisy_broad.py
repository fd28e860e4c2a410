"""The optimiser on a broader bed than Table 1: the 17 DAISY sets, several lengths and two lags.

For each set: w = [u y] centred over the whole set, the first ceil(f T) samples for each fraction f
(default 0.6, 0.7 and 0.8), lags ell (datasets.toml) and ell + 1, errors-in-variables, all weights 1,
the default start, maxiter 100 (as benchmarks/daisy_solver.py otherwise). 17 x 3 x 2 = 102 problems.
Prints the iterations in all, the runs above 50 iterations and those stopped at the limit, and
writes every run (misfit, iterations, converged, seconds) to a JSON file, so that two versions of
the solver can be compared run by run (--compare=OLD.json: runs converged in both whose misfits
differ by more than 1e-7 relative). Not a test: about a minute.

The paths of these non-convex problems branch on rounding, so a change of the optimiser is judged on
the whole bed (and on other fractions, e.g. --fractions=0.65,0.75, that played no part in choosing),
not on one set.

Usage: python benchmarks/daisy_broad.py [--fractions=0.6,0.7,0.8] [--out=runs.json] [--compare=old.json]
"""
import json
import math
import sys
import warnings

import numpy as np

from daisy_solver import DAISY, SETS
from ident import daisy as daisy_sets
from ident.solver import slra
from ident.structure import Structure


def runs(fractions):
    """{"set/fraction/lag": (misfit, iterations, converged, seconds)}."""
    out = {}
    for name in SETS:
        meta = daisy_sets.dataset(name)
        u, y = daisy_sets.load(name, DAISY, download_missing=False)
        w_all = np.hstack([u, y])
        w_all = w_all - w_all.mean(axis=0)
        for fraction in fractions:
            w = w_all[: math.ceil(fraction * len(w_all))]
            for ell in (meta.ell, meta.ell + 1):
                structure = Structure.time_major(w.shape[1], ell, [len(w) - ell])
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    result = slra(structure.params_from_series([w]), structure, (ell + 1) * w.shape[1] - meta.p)
                out[f"{name}/{fraction}/{ell}"] = (result.misfit, result.iterations, result.converged, result.time)
                print(".", end="", flush=True)
    print()
    return out


def main(argv):
    options = dict(a.lstrip("-").partition("=")[::2] for a in argv if a.startswith("--"))
    fractions = [float(f) for f in options.get("fractions", "0.6,0.7,0.8").split(",")]
    results = runs(fractions)
    iterations = [r[1] for r in results.values()]
    print(f"{len(results)} problems: {sum(iterations)} iterations in all, "
          f"{sum(i > 50 for i in iterations)} runs above 50, "
          f"{sum(not r[2] for r in results.values())} at the limit, "
          f"{sum(r[3] for r in results.values()):.1f} s")
    for key, (misfit, n_iter, converged, _) in results.items():
        if n_iter > 50:
            print(f"  {key}: {n_iter} iterations{'' if converged else ' (limit)'}, misfit {misfit:.8g}")
    if "out" in options:
        with open(options["out"], "w") as file:
            json.dump(results, file)
    if "compare" in options:
        with open(options["compare"]) as file:
            old = json.load(file)
        both = [k for k in results if k in old and results[k][2] and old[k][2]]
        changes = [(k, results[k][0] / old[k][0] - 1) for k in both
                   if abs(results[k][0] / old[k][0] - 1) > 1e-7]
        print(f"converged in both: {len(both)}; lower: {sum(c < 0 for _, c in changes)}, "
              f"higher: {sum(c > 0 for _, c in changes)}")
        for key, change in sorted(changes, key=lambda kc: kc[1]):
            print(f"  {key}: {change:+.2e}")


if __name__ == "__main__":
    main(sys.argv[1:])
