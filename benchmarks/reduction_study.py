"""A chosen order on the case of issue 17: a third-order plant with two inputs and two outputs, which
the model class (order ell p) can only fit with order 4 (ell = 2, p = 2). For several random plants and
noise levels, the order-4 model of ident(w, 2, 2) and the order-3 model of ident(w, 2, 2, n=3) are
validated on held-out data against the true plant (literate/10-representations.md, "A model of lower
order"; literate/07-usage.md).

    python benchmarks/reduction_study.py [--seeds 25] [--out benchmarks/reduction_study.json]

Data: T = 1000 samples, white inputs, noise of the given size on every variable (errors-in-variables),
identification on the first 700 samples, validation fit (simulation, initial state by least squares) on
the last 300.
"""
from __future__ import annotations

import argparse
import json
import warnings
from pathlib import Path

import numpy as np

from ident import ident, validate
from ident.representations import make_ss, random_system, simulate
from ident.validation import spectral_radius

NOISE_LEVELS = (0.01, 0.05, 0.1, 0.2)


def third_order_plant(rng):
    """A stable plant with m = 2 inputs, p = 2 outputs and order 3 (not a multiple of p)."""
    three_outputs = random_system(2, 3, 1, rng)
    return make_ss(three_outputs.A, three_outputs.B, np.asarray(three_outputs.C)[:2], np.asarray(three_outputs.D)[:2])


def one_run(seed: int, noise: float) -> dict:
    rng = np.random.default_rng(seed)
    plant = third_order_plant(rng)
    u = rng.standard_normal((1000, 2))
    w = np.hstack([u, simulate(plant, u, rng.standard_normal(3))]) + noise * rng.standard_normal((1000, 4))
    identification, validation = w[:700], w[700:]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        full, info_full, _, _ = ident(identification, 2, 2)
        reduced, info, _, _ = ident(identification, 2, 2, n=3)

    def fit(model):
        return validate(model, validation[:, :2], validation[:, 2:]).mean_fit

    return {"seed": seed, "noise": noise, "fit_true": fit(plant), "fit_order_4": fit(full), "fit_order_3": fit(reduced),
            "radius_order_4": spectral_radius(full), "radius_order_3": spectral_radius(reduced),
            "misfit_order_4": info_full.M, "misfit_order_3": info.M, "method": info.reduction.method}


def summary(runs: list[dict]) -> dict:
    lost_full = np.array([r["fit_true"] - r["fit_order_4"] for r in runs])
    lost_reduced = np.array([r["fit_true"] - r["fit_order_3"] for r in runs])
    return {
        "runs": len(runs),
        "order_4_unstable": int(sum(r["radius_order_4"] >= 1 for r in runs)),
        "order_3_unstable": int(sum(r["radius_order_3"] >= 1 for r in runs)),
        "order_4_within_1_point_of_true_fit": int(np.sum(lost_full < 1)),
        "order_3_within_1_point_of_true_fit": int(np.sum(lost_reduced < 1)),
        "unstable_modes_dropped": int(sum("dropped" in r["method"] for r in runs)),
        "unstable_modes_kept": int(sum("kept" in r["method"] for r in runs)),
        "median_fit_lost_order_3": float(np.median(lost_reduced)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=25, help="number of random plants (each at every noise level)")
    parser.add_argument("--out", type=Path, help="write the runs and the summary as JSON here")
    args = parser.parse_args()
    runs = []
    for seed in range(args.seeds):
        for noise in NOISE_LEVELS:
            runs.append(one_run(seed, noise))
            r = runs[-1]
            print(f"seed {seed:2d} noise {noise:4.2f}: fit true {r['fit_true']:5.1f}, order 4 {r['fit_order_4']:5.1f} "
                  f"(radius {r['radius_order_4']:.3f}), order 3 {r['fit_order_3']:5.1f} ({r['method']})", flush=True)
    result = {"summary": summary(runs), "runs": runs}
    print(json.dumps(result["summary"], indent=1))
    if args.out:
        args.out.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
