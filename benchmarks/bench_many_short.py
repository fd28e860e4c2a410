"""Many short series against one long one: whole `ident` calls, side by side, under both BLAS settings.

The same 7500 samples of a noisy first-order SISO system are identified (m = 1, ell = 1, ident's
defaults) as one series and as 2500 series of 3 samples. The issue (32) measured 237 s for the
2500 series with OpenBLAS's default threads and 5.6 s with one: `initial_states` called `inistate`
once per series, some 5,000 tiny solves and 10,000 numpy calls outside the solver's one-thread
limit. `ident` now runs on one BLAS thread as a whole and solves the initial states of all series
at once; the acceptance is a ratio (2500 series) / (one series) of at most 3.

Each setting runs in a fresh process (the BLAS thread count is read when OpenBLAS loads):
OPENBLAS_NUM_THREADS unset (OpenBLAS's default: as many threads as cores) and set to 1. In each,
the two calls alternate for --rounds rounds after one warm-up call of each, and the medians and
their ratio are printed side by side. With --before DIR (a `src` folder of another checkout, e.g.
from `git archive main src | tar -x -C /tmp/before`) the same runs use that code too, as a column
of its own. The machine may be shared and loaded: the load average is printed with each run, and
only ratios within one process are compared.

Usage: python benchmarks/bench_many_short.py [--rounds N] [--before DIR] [--out FILE]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
N_SAMPLES, SERIES_LENGTH = 7500, 3


def measure(rounds: int) -> dict:
    """Median seconds of ident on one series and on the same samples cut into short series."""
    import numpy as np
    import threadpoolctl

    from ident import ident
    from ident.representations import random_system, simulate

    rng = np.random.default_rng(0)
    system = random_system(1, 1, 1, rng)
    u = rng.standard_normal((N_SAMPLES, 1))
    w = np.hstack([u, simulate(system, u, rng.standard_normal(1))]) + 0.1 * rng.standard_normal((N_SAMPLES, 2))
    short = [w[k:k + SERIES_LENGTH] for k in range(0, N_SAMPLES, SERIES_LENGTH)]
    times = {"one series": [], f"{len(short)} series": []}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for data in (w, short):  # warm-up: imports, caches
            ident(data, 1, 1)
        for _ in range(rounds):
            for name, data in zip(times, (w, short)):
                started = time.perf_counter()
                ident(data, 1, 1)
                times[name].append(time.perf_counter() - started)
    medians = {name: statistics.median(values) for name, values in times.items()}
    one, many = medians.values()
    return {"medians_s": medians, "ratio": many / one, "load_average": os.getloadavg()[0],
            "blas_threads": [lib["num_threads"] for lib in threadpoolctl.threadpool_info()
                             if lib["user_api"] == "blas"]}


def run_setting(source: Path, threads: str | None, rounds: int) -> dict:
    """measure() in a fresh process with `source` first on the path and OPENBLAS_NUM_THREADS as given."""
    env = {key: value for key, value in os.environ.items() if key != "OPENBLAS_NUM_THREADS"}
    if threads is not None:
        env["OPENBLAS_NUM_THREADS"] = threads
    env["PYTHONPATH"] = str(source)
    output = subprocess.run([sys.executable, __file__, "--child", str(rounds)], env=env, check=True,
                            capture_output=True, text=True).stdout
    return json.loads(output.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--before", type=Path, help="a src folder of the code to compare with")
    parser.add_argument("--out", type=Path, help="write the results as JSON there")
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child is not None:
        print(json.dumps(measure(args.child)))
        return
    sources = {"now": ROOT / "src"} | ({"before": args.before} if args.before else {})
    settings = {"default threads": None, "OPENBLAS_NUM_THREADS=1": "1"}
    results = {f"{code}, {setting}": run_setting(source, threads, args.rounds)
               for code, source in sources.items() for setting, threads in settings.items()}
    print(f"{os.cpu_count()} cores; ident(w, 1, 1) on {N_SAMPLES} samples, medians of {args.rounds} rounds")
    print(f"{'code, BLAS threads':40s} {'one series':>11s} {'2500 series':>12s} {'ratio':>6s} {'load':>5s}")
    for name, result in results.items():
        one, many = result["medians_s"].values()
        print(f"{name + ' ' + str(result['blas_threads']):40s} {one:10.3f}s {many:11.3f}s "
              f"{result['ratio']:6.1f} {result['load_average']:5.1f}")
    if args.out:
        args.out.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
