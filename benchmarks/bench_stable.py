"""ident(..., stable=True) on the 17 DAISY sets of Table 1, both modes (issue 34,
30-uncertainty-and-stability.md). Not a test.

Protocol of bench_offset's "protocol" way: the record centred by its means, the first 70 % identifies,
the rest validates (validate's simulation fit, the initial state by least squares), the runner's
settings (maxiter 500, tol 1e-5, refine 1e-12, init "auto"). Three identifications per set and mode:

- unconstrained: ident as before issue 34 (its hold-out fallback switched off here by replacing
  ident.identification.stable_choice with the identity, for this run only);
- default: ident as it is now (with no stable candidate it runs the constrained fit too and chooses
  by a hold-out);
- stable: ident(..., stable=True) with the default margin.

Writes benchmarks/results/stable.json (fits, misfits, spectral radii, seconds). Usage:
python benchmarks/bench_stable.py [SET ...]
"""
from __future__ import annotations

import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import ident.identification as identification
from ident import daisy, ident
from ident.validation import validate

ROOT = Path(__file__).resolve().parents[1]
DAISY = ROOT.parent / "shared" / "daisy"
RESULTS = ROOT / "benchmarks" / "results" / "stable.json"
SETTINGS = {"maxiter": 500, "tol": 1e-5, "refine": 1e-12}
HOLDOUT = 0.3


def run(w_identification, w_validation, m: int, ell: int, mode: str, way: str) -> dict:
    exact = list(range(m)) if mode == "oe" else None
    started = time.perf_counter()
    original = identification.stable_choice
    if way == "unconstrained":
        identification.stable_choice = lambda chosen, *args, **kwargs: (chosen, None)
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            model, info, _, _ = ident(w_identification, m, ell, exct=exact, stable=way == "stable", **SETTINGS)
            fit = float(validate(model, w_validation[:, :m], w_validation[:, m:]).mean_fit)
    except (ValueError, np.linalg.LinAlgError) as error:
        return {"fit": math.nan, "error": str(error), "seconds": time.perf_counter() - started}
    finally:
        identification.stable_choice = original
    radius = float(np.max(np.abs(np.linalg.eigvals(model.A)))) if model.nstates else 0.0
    stability = info.stability
    return {"fit": fit, "misfit": info.M, "spectral_radius": radius, "seconds": time.perf_counter() - started,
            "rule": None if stability is None else stability.rule,
            "constrained": bool(stability is not None and stability.constrained),
            "holdout": None if stability is None else stability.holdout,
            "start": None if stability is None else stability.start}


def main(names) -> None:
    ways, modes = ("unconstrained", "default", "stable"), ("oe", "eiv")
    results = {}
    for info in daisy.table1():
        if names and info.name not in names:
            continue
        u, y = daisy.load(info.name, DAISY, download_missing=False)
        w = np.hstack([u, y])
        w = w - w.mean(axis=0)
        n_identification = math.ceil((1 - HOLDOUT) * len(w))
        results[info.name] = {mode: {way: run(w[:n_identification], w[n_identification:], info.m, info.ell, mode, way)
                                     for way in ways} for mode in modes}
        print(f"{info.name:18s} " + "  ".join(
            f"{mode} " + " ".join(f"{results[info.name][mode][way]['fit']:7.2f} ({results[info.name][mode][way].get('spectral_radius', math.nan):.4f})"
                                  for way in ways) for mode in modes), flush=True)
    for mode in modes:
        fits = {way: np.array([results[name][mode][way]["fit"] for name in results]) for way in ways}
        radii = {way: np.array([results[name][mode][way].get("spectral_radius", math.nan) for name in results]) for way in ways}
        print(f"{mode}: mean fit " + ", ".join(f"{way} {np.nanmean(fits[way]):.2f}" for way in ways)
              + "; largest spectral radius " + ", ".join(f"{way} {np.nanmax(radii[way]):.4f}" for way in ways))
    if not names:
        RESULTS.write_text(json.dumps(results, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
