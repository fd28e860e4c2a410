"""The acceptance figures of issue 14 for misfit, in one run (python benchmarks/misfit_acceptance.py).

1. The paper's lag-14 data (reference/msd_uy.txt): M of the original software's model, of
   ident's model, of an orthogonal and of a diagonal change of its state coordinates.
2. Agreement with a dense least-squares reference (tests/test_smoothing.py's) over random models,
   every setting of the tests: the largest relative difference.
3. Exact trajectories of random models (T = 5..300): the largest M / ||w||^2.
The timings are benchmarks/bench_misfit.py's.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from ident import ident, misfit
from ident.representations import make_ss, observability_index

REFERENCE = Path(__file__).resolve().parents[1] / "reference"  # the original software's results

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_smoothing import agree, dense_misfit, random_models, trajectory_of  # noqa: E402


def paper_data() -> None:
    w = np.loadtxt(REFERENCE / "msd_uy.txt")
    reference = json.loads((REFERENCE / "msd_results.json").read_text())
    original = make_ss(*(np.array(reference["ident"][name]) for name in "ABCD"))
    sysh, info, _, _ = ident(w, 1, 14)
    rng = np.random.default_rng(14)
    Q = np.linalg.qr(rng.standard_normal((14, 14)))[0]
    S = 10.0 ** rng.uniform(-3, 3, 14)
    models = {"original software's model": original, "ident's model": sysh,
              "ident's model, orthogonal Q": make_ss(Q.T @ sysh.A @ Q, Q.T @ sysh.B, sysh.C @ Q, sysh.D),
              "ident's model, diagonal 1e-3..1e3": make_ss(sysh.A * S[None, :] / S[:, None], sysh.B / S[:, None],
                                                          sysh.C * S[None, :], sysh.D)}
    print(f"paper's data, lag 14: ||w||^2 = {np.sum(w ** 2):.3g}; ident's info.M = {info.M:.2e}")
    for name, model in models.items():
        print(f"  {name:36s} M = {misfit(w, model)[0]:.2e}")


def dense_agreement() -> None:
    worst = {}
    for setting, (exact_inputs, missing, wini) in {"errors-in-variables": (False, False, None),
                                                     "output error": (True, False, None),
                                                     "from rest": (False, False, 0),
                                                     "missing values": (False, True, None),
                                                     "given initial samples": (False, False, "past")}.items():
        worst[setting] = 0.0
        for rng, model in random_models(100, 60, orders=(0, 6)):
            n, m = model.nstates, model.ninputs
            lag = observability_index(model) if n else 0
            whole = trajectory_of(model, int(rng.integers(5, 41)) + lag, rng)
            w = whole[lag:] + 0.3 * rng.standard_normal(whole[lag:].shape)
            exact = tuple(range(m)) if exact_inputs else ()
            if exact_inputs:
                w[:, :m] = whole[lag:, :m]
            if missing:
                w[rng.random(w.shape) < 0.2] = np.nan
            given = [whole[:lag]] if wini == "past" else wini
            M = misfit(w, model, exct=exact, wini=given)[0]
            M_dense = dense_misfit(model, w, exact, past=whole[:lag] if wini == "past" else None,
                                   at_rest=wini == 0)[0]
            worst[setting] = max(worst[setting], agree(M, M_dense, w))
    print("dense reference, 60 random models each (n = 0..5, m = 0..2, p = 1..3, T = 5..40), largest relative "
          "difference:")
    for setting, value in worst.items():
        print(f"  {setting:22s} {value:.1e}")


def exact_trajectories() -> None:
    largest = 0.0
    for rng, model in random_models(200, 200, orders=(0, 7)):
        w = trajectory_of(model, int(rng.integers(5, 301)), rng)
        size = np.sum(w ** 2)
        if size > 0:
            largest = max(largest, misfit(w, model)[0] / size)
    print(f"exact trajectories of 200 random models: largest M / ||w||^2 = {largest:.1e}")


if __name__ == "__main__":
    paper_data()
    dense_agreement()
    exact_trajectories()
