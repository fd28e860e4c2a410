"""DAISY Table 1 protocol for the solver: misfit, iterations and time of ident.solver.slra versus the reference.

For each set: w = [u y] (inputs first), every column centred over the whole set, the first
ceil(0.7 T) samples, q = m + p, the lag ell of datasets.toml, Hankel depth ell + 1 (time-major
rows), rank (ell + 1) q - p, all weights 1, the default initial approximation, maxiter 100.
A misfit counts as reaching the reference's when it is at most the reference plus half a unit in the
last digit the reference prints (ballbeam: 2.43137e-3 is printed to 6 digits; the minimum is
2.4313737e-3).
The data are read from ../shared/daisy beside the project. Not a test: it prints a table.

Usage: python benchmarks/daisy_solver.py [MAXITER] [--secant|--no-secant] [SET ...]
"""
import math
import sys
import warnings
from pathlib import Path

import numpy as np

from ident.solver import SLRAWarning, slra
from ident.structure import Structure

DAISY = Path(__file__).resolve().parents[2] / "shared" / "daisy"
SETS = ["erie", "destill", "heating_system", "dryer2", "dryer", "ballbeam", "flutter",
        "robot_arm", "glassfurnace", "thermic_res_wall", "pHdata", "CD_player_arm",
        "winding", "exchanger", "evaporator", "cstr", "steamgen"]
# the reference (MATLAB ident + C++ slra, maxiter 500; reference/README.md): M, iterations, seconds
REFERENCE = {
    "erie": (5.3849193, 118, 0.16), "destill": (2.45990e-5, 50, 0.24),
    "heating_system": (108.68877, 22, 0.06), "dryer2": (361.86964, 500, 14.0),
    "dryer": (2.9416949, 83, 0.37), "ballbeam": (2.43137e-3, 13, 0.06),
    "flutter": (19.406697, 45, 0.25), "robot_arm": (1.323095e-2, 4, 0.03),
    "glassfurnace": (None, None, None), "thermic_res_wall": (16.034069, 15, 0.03),
    "pHdata": (264.37550, 121, 1.09), "CD_player_arm": (9.6896701, 500, 9.6),
    "winding": (59.354296, 18, 0.82), "exchanger": (13.170512, 25, 0.12),
    "evaporator": (1572.9293, 500, 87.2), "cstr": (297.57202, 500, 16.8),
    "steamgen": (19961.967, 9, 9.1),
}


def reference_tolerance(value):
    """Half a unit in the last digit the reference prints (the README gives 5 to 8 significant
    digits): a misfit within this of the reference is the reference's value."""
    mantissa = repr(float(value)).split("e")[0].replace("-", "").replace(".", "").lstrip("0")
    exponent = math.floor(math.log10(abs(value)))
    return 0.5 * 10.0 ** (exponent - len(mantissa) + 1)


def load(name):
    """Identification part of one set: (w, m, p, ell)."""
    from ident import daisy as daisy_sets
    meta = daisy_sets.dataset(name)
    u, y = daisy_sets.load(name, DAISY, download_missing=False)
    w = np.hstack([u, y])
    w = w - w.mean(axis=0)
    return w[: math.ceil(0.7 * len(w))], meta.m, meta.p, meta.ell


def run(name, maxiter=100, secant=None):
    """Solve one set; returns the SLRAResult."""
    w, m, p, ell = load(name)
    n_samples, n_vars = w.shape
    structure = Structure.time_major(n_vars, ell, [n_samples - ell])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SLRAWarning)
        options = {} if secant is None else {"secant": secant}  # None: the solver's default
        return slra(structure.params_from_series([w]), structure, (ell + 1) * n_vars - p,
                    maxiter=maxiter, **options)


def main(argv):
    if not DAISY.is_dir():
        sys.exit(f"DAISY data not found in {DAISY}")
    maxiter = next((int(a) for a in argv if a.isdigit()), 100)
    options = dict(a.lstrip("-").partition("=")[::2] for a in argv if a.startswith("--"))
    secant = False if "no-secant" in options else True if "secant" in options else None
    names = [a for a in argv if not a.isdigit() and not a.startswith("--")] or SETS
    print(f"maxiter {maxiter}, secant={secant}")
    print(f"{'set':17s} {'M (ident)':>14s} {'M (reference)':>14s} {'rel.diff':>9s} "
          f"{'iter':>5s} {'ref it':>6s} {'s':>7s} {'ref s':>7s}  conv  message")
    total, total_reference, all_met = 0.0, 0.0, True
    for name in names:
        result = run(name, maxiter, secant)
        reference_misfit, reference_iterations, reference_seconds = REFERENCE[name]
        total += result.time
        total_reference += reference_seconds or 0.0
        if reference_misfit is None:
            relative, shown = float("nan"), "failed"
        else:
            relative = (result.misfit - reference_misfit) / reference_misfit
            shown = f"{reference_misfit:14.8g}"
            all_met &= result.misfit <= reference_misfit + reference_tolerance(reference_misfit)
        all_met &= result.iterations <= 50
        print(f"{name:17s} {result.misfit:14.8g} {shown:>14s} {relative:9.1e} {result.iterations:5d} "
              f"{str(reference_iterations or '-'):>6s} {result.time:7.3f} {str(reference_seconds or '-'):>7s}  "
              f"{'yes' if result.converged else 'NO ':4s}  {result.message}", flush=True)
    print(f"total solver time {total:.2f} s (reference {total_reference:.1f} s, ratio "
          f"{total / max(total_reference, 1e-300):.3f}); all targets (M <= reference to its printed digits, "
          f"iterations <= 50): {all_met}")


if __name__ == "__main__":
    main(sys.argv[1:])
