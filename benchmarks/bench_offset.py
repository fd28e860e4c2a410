"""Affine identification (ident's offset=True) against centring, on the 17 DAISY sets of Table 1. Not a test.

For each set and mode (output error: inputs exact; errors-in-variables) the raw data (uncentred) are
split as the paper's protocol splits them: the first ceil(0.7 T) samples identify, the rest validate.
Three ways are run with the runner's settings (maxiter 500, tol 1e-5, refine 1e-12, init "auto"),
each validated by simulation on the validation part with its offset applied (validate's fit, the
initial state by least squares):

- affine: ident(w_identification, m, ell, offset=True); validated on w_validation - info.offset;
- centred: ident(w_identification - mean(w_identification)); validated on w_validation - that mean
  (the centring a user can do without the validation data);
- protocol: the paper's protocol, centred by the means of the whole record (identification and
  validation), for reference (it looks at the validation data's mean).

Prints a table, the number of sets on which affine validates at least as well as centred (to 0.05
points) per mode, and writes every number to benchmarks/bench_offset.json.

Usage: python benchmarks/bench_offset.py [SET ...]
"""
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from ident import daisy, ident
from ident.validation import validate

ROOT = Path(__file__).resolve().parents[1]
DAISY = ROOT.parent / "shared" / "daisy"
SETTINGS = {"maxiter": 500, "tol": 1e-5, "refine": 1e-12}
HOLDOUT = 0.3
AS_GOOD = 0.05  # points of fit: "at least as well" allows this much rounding


def fit_of(model, w_validation, levels, m: int) -> float:
    """The mean validation fit of model on w_validation - levels (NaN where it cannot be simulated)."""
    shifted = w_validation - levels
    result = validate(model, shifted[:, :m], shifted[:, m:])
    return float(result.mean_fit)


def run(w_identification, w_validation, m: int, ell: int, mode: str, way: str, record_means) -> dict:
    exact = list(range(m)) if mode == "oe" else None
    started = time.perf_counter()
    if way == "affine":
        data, affine = w_identification, True
    else:
        levels = w_identification.mean(axis=0) if way == "centred" else record_means
        data, affine = w_identification - levels, False
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            model, info, _, _ = ident(data, m, ell, exct=exact, offset=affine, **SETTINGS)
    except (ValueError, np.linalg.LinAlgError) as error:
        return {"fit": math.nan, "error": str(error), "seconds": time.perf_counter() - started}
    if affine:
        levels = info.offset.vector
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        fit = fit_of(model, w_validation, levels, m)
    radius = float(np.max(np.abs(np.linalg.eigvals(model.A)))) if model.nstates else 0.0
    return {"fit": fit, "misfit": info.M, "start": info.start, "spectral_radius": radius,
            "seconds": time.perf_counter() - started}


def main(names) -> None:
    ways, modes = ("affine", "centred", "protocol"), ("oe", "eiv")
    results = {}
    print(f"{'set':18s} " + " ".join(f"{mode + ' ' + way:>14s}" for mode in modes for way in ways), flush=True)
    for info in daisy.table1():
        if names and info.name not in names:
            continue
        u, y = daisy.load(info.name, DAISY, download_missing=False)
        w = np.hstack([u, y])
        n_identification = math.ceil((1 - HOLDOUT) * len(w))
        w_identification, w_validation = w[:n_identification], w[n_identification:]
        results[info.name] = {mode: {way: run(w_identification, w_validation, info.m, info.ell, mode, way, w.mean(axis=0))
                                     for way in ways} for mode in modes}
        print(f"{info.name:18s} " + " ".join(f"{results[info.name][mode][way]['fit']:14.2f}"
                                            for mode in modes for way in ways), flush=True)
    for mode in modes:
        affine = np.array([results[name][mode]["affine"]["fit"] for name in results])
        centred = np.array([results[name][mode]["centred"]["fit"] for name in results])
        protocol = np.array([results[name][mode]["protocol"]["fit"] for name in results])
        as_good = int(np.sum(np.nan_to_num(affine, nan=-np.inf) >= np.nan_to_num(centred, nan=-np.inf) - AS_GOOD))
        as_good_protocol = int(np.sum(np.nan_to_num(affine, nan=-np.inf) >= np.nan_to_num(protocol, nan=-np.inf) - AS_GOOD))
        print(f"{mode}: affine at least as good as centred on {as_good} of {len(results)} sets "
              f"(as the protocol's centring: {as_good_protocol}); mean fit affine {np.nanmean(affine):.2f}, "
              f"centred {np.nanmean(centred):.2f}, protocol {np.nanmean(protocol):.2f} "
              f"(affine failed on {int(np.sum(np.isnan(affine)))})")
    if not names:
        (ROOT / "benchmarks" / "bench_offset.json").write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
