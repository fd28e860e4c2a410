"""Markovsky and Dorfler's interpolation protocol (Automatica 135, 2022, Table 2) with ident's complete.

    python benchmarks/completion_protocol.py [--data-dir ../shared/daisy] [--masks 20]

For each of destill, pHdata, dryer, thermic_res_wall and heating_system (DAISY, as ident.daisy reads
them): the first 75 % of the record identifies, the last 25 % is the test part. Every choice uses the
first 75 % only: its mean is taken off (and added back to the completion), the lag is chosen by
choose_lag on it (lags 1 .. LARGEST_LAG, fewer where the data are too short), the model is ident's
(errors-in-variables), and the prior of the missing inputs is the inputs' mean and spread in it with
the error level of its misfit (InputPrior.from_data). In the test part 20 % of all values are missing
at random (numpy default_rng(seed) masks, seeds 0 .. masks-1); the error is
e = ||w_miss - w_hat_miss|| / ||w_miss|| in %, the median over the masks, for the completion with the
prior and without it (the maximum-likelihood completion, misfit()'s trajectory), and the same error of
each variable over its own missing values (inputs first; the median over the masks).

Writes benchmarks/results/completion_protocol.json. About a minute.
"""
from __future__ import annotations

import argparse
import json
import math
import warnings
from pathlib import Path

import numpy as np

from ident import InputPrior, choose_lag, complete, daisy, ident

SETS = ("destill", "pHdata", "dryer", "thermic_res_wall", "heating_system")
PUBLISHED_METHOD_9 = {"destill": 17.44, "pHdata": 85.71, "dryer": 8.96, "thermic_res_wall": 44.10,
                      "heating_system": 1.35}
PUBLISHED_BEST = {"destill": 9.30, "pHdata": 12.19, "dryer": 7.06, "thermic_res_wall": 3.98, "heating_system": 0.36}
LARGEST_LAG = 10
IDENTIFIED = 0.75
MISSING = 0.2
OUT = Path(__file__).resolve().parent / "results" / "completion_protocol.json"


def chosen_lag(w: np.ndarray, m: int) -> int:
    """choose_lag over lags 1 .. LARGEST_LAG, the largest lags left out where the data are too short for them."""
    for largest in range(LARGEST_LAG, 0, -1):
        try:
            return choose_lag(w, m, range(1, largest + 1)).ell
        except ValueError as error:
            if "too long" not in str(error) and "too short" not in str(error):
                raise
    raise ValueError("no lag fits the data")


def one_set(name: str, data_dir, n_masks: int) -> dict:
    u, y = daisy.load(name, data_dir, download_missing=False)
    w = np.hstack([u, y])
    m = u.shape[1]
    n_identification = math.floor(IDENTIFIED * len(w))
    identification, test = w[:n_identification], w[n_identification:]
    mean = identification.mean(axis=0)
    centred = identification - mean
    ell = chosen_lag(centred, m)
    model, info, _, _ = ident(centred, m, ell)
    prior = InputPrior.from_data(centred, m, info.M)
    errors = {"with_prior": [], "maximum_likelihood": []}
    per_variable = {"with_prior": [], "maximum_likelihood": []}
    for seed in range(n_masks):
        gaps = np.random.default_rng(seed).random(test.shape) < MISSING
        gappy = np.where(gaps, np.nan, test - mean)
        for key, options in (("with_prior", {"input_prior": prior}), ("maximum_likelihood", {})):
            filled = complete(gappy, model, **options).w + mean
            errors[key].append(100 * np.linalg.norm(filled[gaps] - test[gaps]) / np.linalg.norm(test[gaps]))
            per_variable[key].append([100 * np.linalg.norm((filled - test)[gaps[:, j], j]) / np.linalg.norm(test[gaps[:, j], j])
                                      for j in range(w.shape[1])])
    return {"ell": ell, "n": model.nstates, "m": m, "q": w.shape[1], "T": len(w), "n_identification": n_identification,
            "error_with_prior": float(np.median(errors["with_prior"])),
            "error_maximum_likelihood": float(np.median(errors["maximum_likelihood"])),
            "per_variable_with_prior": np.median(per_variable["with_prior"], axis=0).tolist(),
            "per_variable_maximum_likelihood": np.median(per_variable["maximum_likelihood"], axis=0).tolist(),
            "published_method_9": PUBLISHED_METHOD_9[name], "published_best": PUBLISHED_BEST[name]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-dir", default=str(Path(__file__).resolve().parents[2] / "shared" / "daisy"))
    parser.add_argument("--masks", type=int, default=20)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    results = {"protocol": {"identified": IDENTIFIED, "missing": MISSING, "masks": args.masks, "lags": f"1..{LARGEST_LAG}",
                            "benchmark": "benchmarks/completion_protocol.py"}, "sets": {}}
    for name in SETS:
        results["sets"][name] = one_set(name, args.data_dir, args.masks)
        row = results["sets"][name]
        print(f"{name:17s} ell {row['ell']:2d}  e {row['error_with_prior']:7.2f} %  (no prior {row['error_maximum_likelihood']:8.2f} %)"
              f"  published (9) {row['published_method_9']:6.2f}, best {row['published_best']:5.2f}", flush=True)
    OUT.parent.mkdir(exist_ok=True)
    OUT.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
