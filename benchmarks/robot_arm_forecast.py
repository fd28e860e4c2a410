"""Forecast of the DAISY robot arm (m = p = 1) with ident's forecast, 8 samples of past.

    python benchmarks/robot_arm_forecast.py [--data-dir ../shared/daisy]

The protocol (the Behavioral Toolbox's example, as far as the issue states it; its script was not
found): the last HORIZON samples of the record are the forecast window; everything before it is the
data the model is made from: the lag chosen by choose_lag on it (lags 1 .. 10, the package's own
rule), the model identified by ident on it (errors-in-variables, as given: the robot arm's data are
centred already). The PAST = 8 samples just before the window are the past trajectory of forecast,
the window's inputs its future input. Errors: ||y - y_hat|| / ||y|| in % over the whole window
(the last 50 samples of the record) and over its last 10 samples. Model-based: a data-driven forecast
needs an exact reference trajectory, and noisy data have Hankel matrices of full rank.

Writes benchmarks/results/robot_arm_forecast.json. A few seconds.
"""
from __future__ import annotations

import argparse
import json
import warnings
from pathlib import Path

import numpy as np

from ident import choose_lag, daisy, forecast, ident

HORIZON = 50
PAST = 8
LAGS = range(1, 11)
OUT = Path(__file__).resolve().parent / "results" / "robot_arm_forecast.json"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-dir", default=str(Path(__file__).resolve().parents[2] / "shared" / "daisy"))
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    u, y = daisy.load("robot_arm", args.data_dir, download_missing=False)
    w = np.hstack([u, y])
    start = len(w) - HORIZON
    before = w[:start]
    ell = choose_lag(before, 1, LAGS).ell
    model, info, _, _ = ident(before, 1, ell)
    ahead = forecast(model, w[start - PAST:start], w[start:, :1])
    error = ahead.y[:, 0] - y[start:, 0]
    results = {"benchmark": "benchmarks/robot_arm_forecast.py", "horizon": HORIZON, "past": PAST,
               "lags": f"{LAGS.start}..{LAGS.stop - 1}", "ell": ell, "n": model.nstates, "method": ahead.method,
               "error_last_50": float(100 * np.linalg.norm(error) / np.linalg.norm(y[start:, 0])),
               "error_last_10": float(100 * np.linalg.norm(error[-10:]) / np.linalg.norm(y[-10:, 0])),
               "published_data_driven": {"last_50": 3.5531, "last_10": 1.9114},
               "published_n4sid": {"last_50": 3.8398, "last_10": 1.8803}}
    print(json.dumps(results, indent=1))
    OUT.parent.mkdir(exist_ok=True)
    OUT.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
