"""Cost of misfit (the state-space smoother) against the number of samples T = 1e4, 1e5, 1e6.

    python benchmarks/bench_misfit.py [--out benchmarks/bench_misfit.json]

A two-input two-output model of lag 2 (n = 4) on noisy data, errors-in-variables and output error,
best of three runs, with the ratio to the previous T (10 means linear cost); then what costs more:
10 % of the values missing at random (the factor is disturbed at every gap, so most samples are
stepped one by one), and a model whose factor never settles (the paper's lag-14 chain model in
output error: an eigenvalue at 1). Written to a JSON file that literate/16-misfit.md reads.
Timings depend on the machine and its load; compare ratios measured in one run.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from ident import misfit
from ident.representations import make_ss, random_system, simulate

REFERENCE = Path(__file__).resolve().parents[1] / "reference"  # the original software's results


def best_of(call, repeats: int = 3) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return min(times)


def noisy_data(model, n_samples: int, rng) -> np.ndarray:
    u = rng.standard_normal((n_samples, model.ninputs))
    w = np.hstack([u, simulate(model, u, rng.standard_normal(model.nstates))])
    return w + 0.1 * rng.standard_normal(w.shape)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(Path(__file__).with_name("bench_misfit.json")))
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    model = random_system(2, 2, 2, rng)
    rows = []
    for n_samples in (10**4, 10**5, 10**6):
        w = noisy_data(model, n_samples, rng)
        for setting, exact in (("errors-in-variables", None), ("output error", [0, 1])):
            seconds = best_of(lambda: misfit(w, model, exct=exact))
            rows.append({"T": n_samples, "setting": setting, "seconds": seconds})
            print(f"T = {n_samples:>8d}  {setting:20s} {seconds:7.3f} s  {1e6 * seconds / n_samples:6.2f} us/sample")
    w = noisy_data(model, 10**5, rng)
    w[rng.random(w.shape) < 0.1] = np.nan
    seconds = best_of(lambda: misfit(w, model), 1)
    rows.append({"T": 10**5, "setting": "10 % missing", "seconds": seconds})
    print(f"T = {10**5:>8d}  {'10 % missing':20s} {seconds:7.3f} s  {1e6 * seconds / 10**5:6.2f} us/sample")
    results = REFERENCE / "msd_results.json"
    if results.is_file():
        chain = make_ss(*(np.array(json.loads(results.read_text())["ident"][k]) for k in "ABCD"))
        w = noisy_data(chain, 10**4, rng)
        seconds = best_of(lambda: misfit(w, chain, exct=[0]), 1)
        rows.append({"T": 10**4, "setting": "chain, output error", "seconds": seconds})
        print(f"T = {10**4:>8d}  {'chain, output error':20s} {seconds:7.3f} s  {1e6 * seconds / 10**4:6.2f} us/sample")
    machine = {"processor": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
               "python": platform.python_version(), "numpy": np.__version__}
    Path(args.out).write_text(json.dumps({"machine": machine, "rows": rows}, indent=1) + "\n")
    print(f"written to {args.out}")


if __name__ == "__main__":
    main()
