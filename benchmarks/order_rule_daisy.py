"""Issue 35: the order chosen by `choose_order` on the 17 DAISY sets of Table 1, against n = ell p. Not a test.

For each set, the paper's protocol as the DAISY runner applies it (`ident.daisy_runner.protocol_split`:
centred, the first 70 % identify, the last 30 % validate), output error (the inputs exact), Table 1's m
and ell, the runner's solver settings (maxiter 500, tol 1e-5, refine 1e-12):

- `choose_order` on the identification part alone chooses n in 1..ell p (its own hold-out: the last 30 %
  of the identification part); the validation part is not used for the choice;
- the model of lag ell identified on the whole identification part, as the runner identifies it, and its
  reductions to every order n (what `ident(w, m, ell, n=n)` returns), each validated on the validation
  part with `validate`, as the runner validates.

Scored: the chosen order validates at least as well as n = ell p (to 0.05 point). Besides the package's
rule two others are scored from the same hold-out fits: the smallest order within 1 point of the best
(choose_lag's rule) and the best. Writes benchmarks/results/order_rule_daisy.json. Takes about two
minutes on one core.

Usage: python benchmarks/order_rule_daisy.py [DATA_DIR]   (default ../shared/daisy)
"""
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from ident import choose_order
from ident.daisy import table1
from ident.daisy_runner import REFINE, SETTINGS, protocol_split
from ident.order_choice import reduced_models
from ident.solver.threads import one_blas_thread
from ident.validation import LAG_FIT_POINTS, validate

TIE = 0.05  # points: a validation fit this close to ell p's counts as as good


def other_rules(orders, holdout_fits):
    scores = np.where(np.isnan(holdout_fits), -np.inf, holdout_fits)
    best = scores.max()
    return {"smallest within 1 point of the best": next(n for n, s in zip(orders, scores) if s >= best - LAG_FIT_POINTS),
            "best": orders[int(np.argmax(scores))]}


def run_set(info, directory):
    _, split = protocol_split(info.name, directory, None, False)
    identification, validation = split.identification, split.validation
    m, ell = info.m, info.ell
    options = {**SETTINGS, "refine": REFINE}
    started = time.perf_counter()
    with warnings.catch_warnings(), one_blas_thread():
        warnings.simplefilter("ignore")
        choice = choose_order(identification, m, ell, exct=range(m), **options)
        models, _, messages = reduced_models(identification, m, ell, choice.orders, range(m), "truncation",
                                             {"init": "auto", **options})
    validation_fits = [float("nan") if model is None else validate(model, validation[:, :m], validation[:, m:]).mean_fit
                       for model in models]
    chosen = {"choose_order": choice.n, **other_rules(choice.orders, choice.holdout_fits)}
    ell_p_fit = validation_fits[-1]
    return {"name": info.name, "m": m, "p": info.p, "ell": ell, "ell_p": ell * info.p, "orders": choice.orders,
            "n_estimation": choice.n_estimation, "n_holdout": choice.n_holdout, "n_validation": len(validation),
            "holdout_fits": [round(float(x), 3) for x in choice.holdout_fits],
            "validation_fits": [round(float(x), 3) for x in validation_fits],
            "chosen": chosen, "chosen_fit": {rule: round(validation_fits[choice.orders.index(n)], 3) for rule, n in chosen.items()},
            "ell_p_fit": round(ell_p_fit, 3),
            "as_good": {rule: bool(validation_fits[choice.orders.index(n)] >= ell_p_fit - TIE) for rule, n in chosen.items()},
            "refused": [x for x, model in zip(messages, models) if model is None],
            "seconds": round(time.perf_counter() - started, 1)}


def main(argv):
    directory = argv[0] if argv else str(Path(__file__).resolve().parents[1].parent / "shared" / "daisy")
    rows = []
    for info in table1():
        row = run_set(info, directory)
        rows.append(row)
        print(f"{row['name']:18s} ell p {row['ell_p']}: chosen {row['chosen']}, validation {row['chosen_fit']} vs "
              f"ell p {row['ell_p_fit']} ({row['seconds']} s)", flush=True)
    rules = list(rows[0]["chosen"])
    summary = {"sets": len(rows), "tie_points": TIE,
               "as_good": {rule: sum(row["as_good"][rule] for row in rows) for rule in rules},
               "reduced": {rule: sum(row["chosen"][rule] < row["ell_p"] for row in rows) for rule in rules},
               "seconds": round(sum(row["seconds"] for row in rows), 1)}
    out = Path(__file__).resolve().parent / "results" / "order_rule_daisy.json"
    out.write_text(json.dumps({"benchmark": "benchmarks/order_rule_daisy.py", "mode": "oe", "summary": summary,
                               "sets": rows}, indent=1) + "\n")
    print(summary)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1:])
