"""Issue 35's acceptance for the order inside the misfit: ident(w, m, ell, n=n, order_fit="misfit") against
balanced truncation followed by misfit() (ident's n= alone), on random systems whose order n is below
ell p. Not a test.

Cases in turn: m = 1 with indices (2, 1) at ell = 2; m = 2 with (3, 2, 1) at ell = 3; SISO order 3
at ell = 4; m = 1 with (2, 2) at ell = 3 from three series of 150 samples; errors in variables and
output error (exct = the inputs) alternately; 300 samples, 10 % noise on every variable (OE: on the
outputs only). Scored: the misfit fit's misfit is at most the truncation's (to 1e-10 relative).

Writes benchmarks/results/order_fit.json. Takes a few minutes.

Usage: python benchmarks/order_fit_acceptance.py [CASES]   (default 40)
"""
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from ident import ident
from ident.data_complexity import system_with_lags
from ident.representations import make_ss, simulate

CASES = [(1, (2, 1), 2, [300]), (2, (3, 2, 1), 3, [300]), (1, (3,), 4, [300]), (1, (2, 2), 3, [150, 150, 150])]


def main(argv):
    cases = int(argv[0]) if argv else 40
    rng = np.random.default_rng(3500)
    rows = []
    for case in range(cases):
        m, lags, ell, lengths = CASES[case % len(CASES)]
        output_error = case % 2 == 1
        A, B, C, D = system_with_lags(lags, m, rng)
        series = []
        for length in lengths:
            u = rng.standard_normal((length, m))
            w = np.hstack([u, simulate(make_ss(A, B, C, D), u, rng.standard_normal(sum(lags)))])
            noisy = w + 0.1 * w.std(axis=0) * rng.standard_normal(w.shape)
            if output_error:
                noisy[:, :m] = w[:, :m]
            series.append(noisy)
        options = {"n": sum(lags), "exct": list(range(m)) if output_error else None}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            started = time.perf_counter()
            _, truncated, _, _ = ident(series, m, ell, **options)
            middle = time.perf_counter()
            _, fitted, _, _ = ident(series, m, ell, order_fit="misfit", **options)
            ended = time.perf_counter()
        rows.append({"m": m, "lags": list(lags), "ell": ell, "series": len(lengths), "mode": "oe" if output_error else "eiv",
                     "truncation": truncated.M, "misfit_fit": fitted.M, "method": fitted.reduction.method,
                     "seconds": [round(middle - started, 2), round(ended - middle, 2)]})
        print(rows[-1], flush=True)
    at_most = sum(row["misfit_fit"] <= row["truncation"] * (1 + 1e-10) for row in rows)
    ratios = [row["misfit_fit"] / row["truncation"] for row in rows]
    summary = {"cases": cases, "at_most_truncation": at_most, "median_ratio": float(np.median(ratios)),
               "smallest_ratio": float(np.min(ratios)), "improved_by_1_percent": sum(r < 0.99 for r in ratios)}
    print(summary)
    out = Path(__file__).resolve().parent / "results" / "order_fit.json"
    out.write_text(json.dumps({"benchmark": "benchmarks/order_fit_acceptance.py", "summary": summary, "rows": rows}, indent=1) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1:])
