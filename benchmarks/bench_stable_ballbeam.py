"""Is there a better stable model of DAISY's ball and beam? (issue 34, 30-uncertainty-and-stability.md).
Not a test.

The plant is unstable (unconstrained models of spectral radius about 1.03), and stable=True loses most of
its validation fit there. This study runs the stability-constrained fit (`ident.stability.constrained_fit`,
margin 1e-3) from many starts on bench_stable's protocol (the record centred, the first 70 % identifies,
the rest validates by simulation, lag of Table 1, the runner's settings) in both modes:

- "candidates": each candidate of init="auto" with its poles pulled inside (what stable=True did before
  the clipped start);
- "clipped": the unconstrained optimum with only its unstable poles moved onto the bound
  (`ident.stability.clipped`), the numerator kept;
- "continuation": the bound lowered from the unconstrained radius to 1 - margin in 7 steps, each fit
  warm-started from the last;
- "grid": the optimum's numerator with the denominator's roots set to each pair of a grid of real poles
  (0 to 0.998) and of complex pairs (moduli 0.9, 0.99, 0.998, angles 0.02, 0.1, 0.3 rad).

For every start: the constrained misfit, the spectral radius and the validation fit. Writes
benchmarks/results/stable_ballbeam.json. Usage: python benchmarks/bench_stable_ballbeam.py
"""
from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np

import ident.identification as identification
import ident.stability as stability
from ident import daisy, ident, kernel_to_ss
from ident.solver.cost import Problem
from ident.uncertainty import normalised
from ident.validation import validate

ROOT = Path(__file__).resolve().parents[1]
DAISY = ROOT.parent / "shared" / "daisy"
RESULTS = ROOT / "benchmarks" / "results" / "stable_ballbeam.json"
SETTINGS = {"maxiter": 500, "tol": 1e-5, "refine": 1e-12}
MARGIN = 1e-3
GRID = (0.0, 0.5, 0.8, 0.9, 0.95, 0.97, 0.98, 0.99, 0.995, 0.998)


def with_poles(kernel, m: int, ell: int, poles) -> np.ndarray:
    """The SISO kernel (P_ell = 1) with P's roots set to poles, Q kept."""
    blocks = np.array(kernel, dtype=float).reshape(1, ell + 1, -1)
    coefficients = np.real(np.poly(poles))  # highest power first
    blocks[0, :, m:] = -coefficients[::-1, None]
    return blocks.reshape(1, -1)


def unconstrained_problem(w_identification, m: int, ell: int, exact):
    """ident's unconstrained optimum, its candidates and the solver's problem (caught at stable_choice)."""
    caught = {}
    original = identification.stable_choice

    def catching(chosen, attempts, problem, *args, **kwargs):
        caught.update(chosen=chosen, attempts=attempts, problem=problem, exponent=args[2])  # args: m, ell, exponent
        return chosen, None
    identification.stable_choice = catching
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ident(w_identification, m, ell, exct=exact, **SETTINGS)
    finally:
        identification.stable_choice = original
    return caught


def main() -> None:
    info = next(i for i in daisy.table1() if i.name == "ballbeam")
    m, ell, bound = info.m, info.ell, 1 - MARGIN
    u, y = daisy.load(info.name, DAISY, download_missing=False)
    w = np.hstack([u, y])
    w = w - w.mean(axis=0)
    cut = math.ceil(0.7 * len(w))
    w_validation = w[cut:]
    results = {"lag": ell, "margin": MARGIN}
    for mode in ("oe", "eiv"):
        caught = unconstrained_problem(w[:cut], m, ell, list(range(m)) if mode == "oe" else None)
        problem = Problem(caught["problem"].parameters, caught["problem"].structure)
        optimum = stability.in_chart(caught["chosen"].candidate.Rh)

        def measured(kernel, start: str) -> dict:
            kernel = normalised(kernel)
            state = problem.evaluate(kernel)
            model = kernel_to_ss(kernel, m, ell, cond_warn=np.inf)
            with np.errstate(all="ignore"):
                fit = float(validate(model, w_validation[:, :m], w_validation[:, m:]).mean_fit)
            return {"start": start, "misfit": float(np.ldexp(state.cost, 2 * caught["exponent"])),
                    "spectral_radius": stability.spectral_radius(kernel, m, ell), "fit": fit}

        def fitted(start_kernel, start: str) -> dict | None:
            try:
                kernel = stability.constrained_fit(problem, start_kernel, m, ell, bound, SETTINGS["maxiter"],
                                                   SETTINGS["tol"])[0]
                return measured(kernel, start)
            except (ValueError, np.linalg.LinAlgError) as error:
                return {"start": start, "error": str(error)}

        runs = [measured(optimum, "unconstrained")]
        runs += [fitted(stability.pulled_inside(stability.in_chart(a.candidate.Rh), m, ell, bound),
                        f"candidates: {a.candidate.start}") for a in caught["attempts"] if not a.candidate.error]
        runs.append(fitted(stability.pulled_inside(stability.clipped(optimum, m, ell, stability.ON_THE_BOUND * bound),
                                                   m, ell, bound, share=stability.ON_THE_BOUND), "clipped"))
        kernel = optimum
        for step_bound in np.geomspace(stability.spectral_radius(optimum, m, ell), bound, 8)[1:]:
            kernel = stability.constrained_fit(problem, stability.pulled_inside(kernel, m, ell, step_bound,
                                                                                share=stability.ON_THE_BOUND),
                                               m, ell, step_bound, SETTINGS["maxiter"], SETTINGS["tol"])[0]
        runs.append(measured(kernel, "continuation"))
        pairs = [(a, b) for i, a in enumerate(GRID) for b in GRID[i:]]
        pairs += [(r * np.exp(1j * angle), r * np.exp(-1j * angle)) for r in (0.9, 0.99, 0.998) for angle in (0.02, 0.1, 0.3)]
        runs += [fitted(with_poles(optimum, m, ell, pair), "grid: " + ", ".join(f"{p:.3g}" for p in pair)) for pair in pairs]
        results[mode] = runs
        ok = [r for r in runs[1:] if "misfit" in r]
        least = min(ok, key=lambda r: r["misfit"])
        best = max(ok, key=lambda r: r["fit"])
        print(f"{mode}: unconstrained misfit {runs[0]['misfit']:.6g} fit {runs[0]['fit']:.2f}; least constrained misfit "
              f"{least['misfit']:.6g} ({least['start']}, fit {least['fit']:.2f}); best fit {best['fit']:.2f} "
              f"({best['start']}, misfit {best['misfit']:.6g}); {len(ok)} fits", flush=True)
    RESULTS.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
