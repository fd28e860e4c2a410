"""Which rule chooses the lag? Measured on the 17 DAISY sets of Table 1, both modes. Not a test.

For each set (centred, the first ceil(0.7 T) samples identify, the rest validate: the paper's
protocol) and mode (output error, errors-in-variables), and each lag ell = 1 .. 5 that the data
allow, with ident's defaults (init="auto", maxiter 100, as choose_lag runs it):

- the model identified on the whole identification part: its misfit M (the paper's trade-off curve,
  from which the information criteria are computed) and its validation fit on the validation part
  (used only to score the rules, never by them);
- the model identified on the first ceil(0.7 T_i) samples of the identification part and its fit
  on the rest of the identification part (the hold-out rule's evidence).

Then each rule chooses a lag from the identification data alone, and is scored by the validation
fit of the model of that lag identified on the whole identification part (maxiter 100): the knee
of the misfit curve (the first lag after which the misfit falls by less than a factor of 2), AIC,
BIC, the hold-out rule (the lag of the best hold-out fit; and the smallest lag within 1 point of
it), Table 1's lag, and the oracle (the best validation fit, which no rule can know).

Writes benchmarks/lag_rules.json (every number) and prints the table of the choices and the means.
Takes about half an hour on the development machine (the sweeps are about 340 identifications of
three starts each).

Usage: python benchmarks/lag_rules.py [SET ...] [--out=FILE] [--evaluate=FILE]
"""
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from ident import daisy, ident
from ident.validation import split_for_validation, validate

ROOT = Path(__file__).resolve().parents[1]
DAISY = ROOT.parent / "shared" / "daisy"
LAGS = range(1, 6)
HOLDOUT = 0.3
MAXITER = 100


def identify(w, m, ell, exact):
    """ident with the defaults; None if the data are too short or identification fails."""
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            return ident(w, m, ell, exct=exact, maxiter=MAXITER)
    except ValueError as error:
        return str(error)


def fit_of(model, w, m):
    if isinstance(model, str) or model is None:
        return None
    return validate(model[0], w[:, :m], w[:, m:]).mean_fit


def sweep(name):
    info = daisy.dataset(name)
    u, y = daisy.load(name, DAISY, download_missing=False)
    split = split_for_validation(u, y, 0.3)
    w_id, w_val = split.identification, split.validation
    n_est = math.ceil((1 - HOLDOUT) * len(w_id))
    w_est, w_check = w_id[:n_est], w_id[n_est:]
    m = info.m
    out = {"m": m, "p": info.p, "T_identification": len(w_id), "table_lag": info.ell, "modes": {}}
    for mode in ("oe", "eiv"):
        exact = list(range(m)) if mode == "oe" else None
        rows = {}
        for ell in LAGS:
            started = time.perf_counter()
            whole = identify(w_id, m, ell, exact)
            inner = identify(w_est, m, ell, exact)
            rows[ell] = {
                "misfit": None if isinstance(whole, str) else whole[1].M,
                "start": None if isinstance(whole, str) else whole[1].start,
                "validation_fit": fit_of(whole, w_val, m),
                "holdout_fit": fit_of(inner, w_check, m),
                "error": whole if isinstance(whole, str) else (inner if isinstance(inner, str) else ""),
                "seconds": time.perf_counter() - started,
            }
            print(f"{name:17s} {mode:3s} ell {ell}: M {rows[ell]['misfit']}, validation "
                  f"{rows[ell]['validation_fit']}, hold-out {rows[ell]['holdout_fit']}", flush=True)
        out["modes"][mode] = rows
    return out


def n_parameters(m, p, ell):
    """Kernel parameters p ((ell + 1) q - p) and the initial state ell p."""
    return p * ((ell + 1) * (m + p) - p) + ell * p


def rules(result, mode):
    """The lag each rule chooses from the identification data (None if it cannot)."""
    m, p, T = result["m"], result["p"], result["T_identification"]
    rows = {int(k): v for k, v in result["modes"][mode].items()}
    with_misfit = [ell for ell in sorted(rows) if rows[ell]["misfit"] is not None]
    n_corrected = T * (p if mode == "oe" else m + p)
    chosen = {"table 1": result["table_lag"]}

    def criterion(penalty):
        return {ell: n_corrected * math.log(max(rows[ell]["misfit"], 1e-300) / n_corrected)
                + penalty * n_parameters(m, p, ell) for ell in with_misfit}

    for name, penalty in (("AIC", 2.0), ("BIC", math.log(n_corrected))):
        values = criterion(penalty)
        chosen[name] = min(values, key=values.get) if values else None
    knee = None
    for ell in with_misfit:
        later = [x for x in with_misfit if x > ell]
        if later and rows[later[0]]["misfit"] > 0.5 * rows[ell]["misfit"]:
            knee = ell
            break
    chosen["knee"] = knee if knee is not None else (with_misfit[-1] if with_misfit else None)
    holdout = {ell: rows[ell]["holdout_fit"] for ell in sorted(rows) if rows[ell]["holdout_fit"] is not None
               and rows[ell]["misfit"] is not None}
    if holdout:
        best = max(holdout.values())
        chosen["hold-out"] = max(holdout, key=holdout.get)
        chosen["hold-out, within 1 point"] = min(ell for ell, f in holdout.items() if f >= best - 1.0)
    else:
        chosen["hold-out"] = chosen["hold-out, within 1 point"] = None
    fits = {ell: rows[ell]["validation_fit"] for ell in with_misfit if rows[ell]["validation_fit"] is not None}
    chosen["oracle"] = max(fits, key=fits.get) if fits else None
    return chosen, fits


def evaluate(results):
    names = ["table 1", "knee", "AIC", "BIC", "hold-out", "hold-out, within 1 point", "oracle"]
    summary = {}
    for mode in ("oe", "eiv"):
        print(f"\n{mode}: lag chosen (validation fit %) per rule")
        print(f"{'set':17s} " + " ".join(f"{n[:12]:>14s}" for n in names))
        scores = {n: [] for n in names}
        for name, result in results.items():
            chosen, fits = rules(result, mode)
            cells = []
            for n in names:
                ell = chosen[n]
                fit = fits.get(ell, 0.0) if ell is not None else 0.0
                scores[n].append(fit)
                cells.append(f"{'-' if ell is None else ell:>3} ({fit:5.1f})  ")
            print(f"{name:17s} " + " ".join(cells))
        means = {n: float(np.mean(v)) for n, v in scores.items()}
        print(f"{'mean':17s} " + " ".join(f"{means[n]:14.1f}" for n in names))
        summary[mode] = means
    return summary


def main(argv):
    options = dict(a.lstrip("-").partition("=")[::2] for a in argv if a.startswith("--"))
    if "evaluate" in options:
        evaluate(json.loads(Path(options["evaluate"]).read_text())["sets"])
        return
    names = [a for a in argv if not a.startswith("--")] or [d.name for d in daisy.table1()]
    out = Path(options.get("out", ROOT / "benchmarks" / "lag_rules.json"))
    started = time.perf_counter()
    results = {name: sweep(name) for name in names}
    summary = evaluate(results)
    out.write_text(json.dumps({"lags": list(LAGS), "holdout": HOLDOUT, "maxiter": MAXITER, "sets": results,
                               "mean_validation_fit": summary,
                               "seconds": time.perf_counter() - started}, indent=1))
    print(f"wrote {out} ({time.perf_counter() - started:.0f} s)")


if __name__ == "__main__":
    main(sys.argv[1:])
