"""weights="auto" measured on DAISY (issue 29), for 32-missing-data.md.

    python benchmarks/weights_auto_daisy.py [--sets NAME ...] [--budget SECONDS]
                                            [--out benchmarks/results/weights_auto_daisy.json]

For every data set of Table 1 in both modes (OE: the inputs exact; EIV), by the protocol of the DAISY
runner (19-daisy-runner.md: the data centred, the last 30 % held out for validation, ident's default
starts, maxiter 500, tol 1e-5, refine 1e-12): the validation fit (the mean over the outputs, as the
table) of the model identified with raw weights (None) and with weights="std", and the choice that
weights="auto" makes on the identification data (ident's own rule, ident.incomplete.chosen_weights,
called with the arguments ident passes it: a model on the first 70 % of the identification data with
each weighting, simulated on its last 30 %, raw on a tie). ident(w, weights="auto") then identifies
from all of the identification data with the chosen weights, so its model is the raw or the "std"
one above, and its validation fit is theirs. Sets are run in the order of Table 1 until the budget of
seconds is spent; the file says which were run.
"""
from __future__ import annotations

import argparse
import json
import platform
import time
import warnings
from pathlib import Path

import numpy as np

from ident import ident
from ident.daisy import table1
from ident.daisy_runner import REFINE, SETTINGS, protocol_split
from ident.incomplete import chosen_weights
from ident.solver.threads import one_blas_thread
from ident.validation import validate

ROOT = Path(__file__).resolve().parents[1]


def mode_record(w, m: int, ell: int, mode: str) -> dict:
    """The fits of raw, "std" and "auto" on the validation part, and auto's choice, for one set and mode."""
    exact = list(range(m)) if mode == "oe" else None
    identification, validation = w
    fits, seconds = {}, {}
    for label, weights in (("raw", None), ("std", "std")):
        started = time.perf_counter()
        model = ident(identification, m, ell, exct=exact, weights=weights, refine=REFINE, **SETTINGS)[0]
        seconds[label] = time.perf_counter() - started
        fits[label] = float(validate(model, validation[:, :m], validation[:, m:]).mean_fit)
    started = time.perf_counter()
    choice = chosen_weights(ident, [identification], "auto", m, ell, exact or [], [None],
                            {"init": "auto", **SETTINGS})
    seconds["auto_choice"] = time.perf_counter() - started
    label = "raw" if choice is None else "std"
    fits["auto"] = fits[label]
    return {"choice": label, "fit": fits, "seconds": seconds}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sets", nargs="*", default=None, help="data sets of Table 1 (default: all 17, in order)")
    parser.add_argument("--budget", type=float, default=600.0, help="seconds after which no further set is started")
    parser.add_argument("--data-dir", default=str(ROOT.parent / "shared" / "daisy"))
    parser.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "weights_auto_daisy.json"))
    args = parser.parse_args()
    names = args.sets or [d.name for d in table1()]
    started, records, skipped = time.perf_counter(), [], []
    for name in names:
        if time.perf_counter() - started > args.budget:
            skipped.append(name)
            continue
        info, split = protocol_split(name, args.data_dir, None, False)
        for mode in ("oe", "eiv"):
            with one_blas_thread(), warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.simplefilter("ignore")  # non-convergence and instability: the fit says what they cost
                try:
                    record = mode_record((split.identification, split.validation), info.m, info.ell, mode)
                except (ValueError, np.linalg.LinAlgError) as error:
                    record = {"error": str(error)}
            records.append({"set": name, "mode": mode, **record})
            print(name, mode, record.get("choice"), record.get("fit"), flush=True)
    result = {"what": "DAISY Table 1 by the runner's protocol: validation fits of raw, weights='std' and "
                      "weights='auto' (its choice by a hold-out of the last 30 % of the identification data)",
              "settings": {**SETTINGS, "refine": REFINE, "init": "auto"}, "runs": records, "skipped": skipped,
              "seconds": time.perf_counter() - started,
              "machine": {"processor": platform.machine(), "python": platform.python_version()}}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
