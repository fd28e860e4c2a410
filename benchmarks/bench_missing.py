"""Cost of identification with missing samples against the complete case, in one run (issue 29, point 5).

    python benchmarks/bench_missing.py [--out benchmarks/results/bench_missing.json] [--memory-sizes 100000 300000 1000000]

A two-input two-output model of lag 2 (n = 4) on noisy data (errors-in-variables, noise 0.1),
T = 1e5: ident on the complete data and on the data with 50 % of the values missing at random
(the time per iteration: the solver's for the complete data, one evaluation of the exact misfit
with J^T J and J^T r formed from the banded factor, which is what an iteration of the refinement
costs, for the missing data; and with the Jacobian itself, by the banded system and by the sparse
one, as the refinement evaluated it before). With
half of all values missing, errors-in-variables data do not determine a model (2 T observed values
against the 2 T + n degrees of freedom of a trajectory: ident refuses them), so ident runs on data
with half of the output values missing, and the evaluation is timed on both patterns;
misfit() at 10 % missing against the complete data, whole calls side by side (the Gram matrix with its
corrections of 33-banded-missing-data.md, which answers for the smoother of 16-misfit.md there, and the
same call with that road closed, the banded LU answering), the smoother itself and the sparse
saddle-point evaluation at 10 % missing; and the peak memory of ident at
10 % missing for growing T (up to 1e6), and of one evaluation of the refinement (T = 1e5 and 1e6;
with the normal equations and with the Jacobian), each in a fresh process. literate/33-banded-missing-data.md reads the JSON.
Timings depend on the machine and its load; compare the ratios measured in one run. The complete
solver's iteration and the evaluations by the banded system are the least of REPEATS runs, misfit()'s
three calls the least of MISFIT_ROUNDS rounds.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from ident import ident, misfit
from ident.incomplete import in_chart, kernel_solution, sparse_solution
from ident.representations import random_system, simulate, ss_to_kernel
from ident.smoothing import smoothed_misfit


def timed(call, repeats: int = 1):
    """(seconds, value) of call, the least time of `repeats` runs: on a shared machine one run can
    take twice as long as the next."""
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        value = call()
        best = min(best, time.perf_counter() - start)
    return best, value


REPEATS = 3  # runs of each timing below the ident runs (the least time is recorded)
MISFIT_ROUNDS = 9  # rounds of misfit() complete, with gaps, and with gaps by the LU, alternating


def interleaved(calls: dict, rounds: int):
    """(name -> least seconds, name -> last value) of the calls, alternating within each round: on a
    shared machine only calls measured side by side compare."""
    best, values = dict.fromkeys(calls, np.inf), {}
    for _ in range(rounds):
        for name, call in calls.items():
            start = time.perf_counter()
            values[name] = call()
            best[name] = min(best[name], time.perf_counter() - start)
    return best, values


def without_gram(call):
    """call() with misfit()'s Gram-matrix road closed: the banded LU answers, as it did before that road."""
    from ident import banded_misfit
    original = banded_misfit.gram_solution
    banded_misfit.gram_solution = lambda *args: None
    try:
        return call()
    finally:
        banded_misfit.gram_solution = original


def noisy_data(n_samples: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    model = random_system(2, 2, 2, rng)
    u = rng.standard_normal((n_samples, 2))
    w = np.hstack([u, simulate(model, u, rng.standard_normal(model.nstates))])
    return model, w + 0.1 * rng.standard_normal(w.shape), rng


def with_gaps(w, fraction: float, rng) -> np.ndarray:
    return np.where(rng.random(w.shape) < fraction, np.nan, w)


PEAK = ("import re, resource; peak = lambda: float(re.search(r'VmHWM:\\s+(\\d+)', open('/proc/self/status').read()).group(1)) "
        "/ 1024 if __import__('os').path.exists('/proc/self/status') else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024; ")
# VmHWM, the peak of the process's own memory: ru_maxrss would carry the parent's resident memory over
# the fork and the exec into the child (this script holds about 1 GiB when it starts the children)


def peak_memory(n_samples: int) -> dict:
    """ident at 10 % missing in a fresh process: its peak resident memory (MiB) and time."""
    code = (PEAK + "import time, numpy as np, sys; sys.path.insert(0, %r); import bench_missing as b; "
            "model, w, rng = b.noisy_data(%d); w = b.with_gaps(w, 0.1, rng); "
            "from ident import ident; s = time.perf_counter(); ident(w, 2, 2, init='lra'); "
            "print(time.perf_counter() - s, peak())"
            % (str(Path(__file__).parent), n_samples))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    return {"T": n_samples, "seconds": float(out[0]), "peak_MiB": float(out[1])}


def evaluation(kernel, values, weights, form: str):
    """One evaluation of the refinement: the exact misfit with J^T J and J^T r formed from the factor
    (form "normal", what ident's refinement does), or with the Jacobian itself (form "jacobian", before)."""
    if form == "normal":
        return kernel_solution(kernel, values, weights, normal=True).normal_equations()
    return kernel_solution(kernel, values, weights, jacobian=True).jacobian


def evaluation_memory(n_samples: int, form: str = "normal") -> dict:
    """One evaluation of the refinement (see `evaluation`) at 10 % missing, in a fresh process: its
    peak resident memory (MiB) and time."""
    code = (PEAK + "import time, numpy as np, sys; sys.path.insert(0, %r); import bench_missing as b; "
            "from ident.incomplete import in_chart; from ident.representations import ss_to_kernel; "
            "model, w, rng = b.noisy_data(%d); w = b.with_gaps(w, 0.1, rng); kernel = in_chart(ss_to_kernel(model, 2)); "
            "s = time.perf_counter(); b.evaluation(kernel, np.nan_to_num(w), np.where(np.isnan(w), 0.0, 1.0), %r); "
            "print(time.perf_counter() - s, peak())"
            % (str(Path(__file__).parent), n_samples, form))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    return {"T": n_samples, "form": form, "seconds": float(out[0]), "peak_MiB": float(out[1])}


def band_size(n_samples: int) -> dict:
    """The band that the LU factors at 10 % missing (the evaluations' data): its half-bandwidth, rows,
    columns and MiB."""
    from ident.banded_misfit import saddle_band, slots
    model, w, rng = noisy_data(n_samples)
    missing = np.isnan(with_gaps(w, 0.1, rng))
    kernel = in_chart(ss_to_kernel(model, 2))
    blocks = kernel.reshape(2, 3, 4).transpose(1, 0, 2)
    lam_start, z_at = slots(missing, 2, 2)
    band, half = saddle_band(blocks, np.where(missing, 0.0, 1.0), np.nonzero(missing), lam_start, z_at, 1e-10)
    return {"T": n_samples, "half": half, "rows": band.shape[0], "columns": band.shape[1], "MiB": band.nbytes / 2**20}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=str(Path(__file__).parent / "results" / "bench_missing.json"))
    parser.add_argument("--samples", type=int, default=100_000)
    parser.add_argument("--memory-sizes", type=int, nargs="*", default=[20_000, 100_000, 1_000_000])
    parser.add_argument("--evaluation-sizes", type=int, nargs="*", default=[100_000, 1_000_000])
    parser.add_argument("--only-evaluation-memory", action="store_true",
                        help="measure only the evaluations' memory and add it to the existing results file")
    args = parser.parse_args()
    if args.only_evaluation_memory:
        record = json.loads(Path(args.out).read_text())
        record["evaluation_memory"] = [evaluation_memory(size, form) for form in ("normal", "jacobian")
                                       for size in args.evaluation_sizes]
        Path(args.out).write_text(json.dumps(record, indent=1) + "\n")
        print(json.dumps(record["evaluation_memory"], indent=1))
        return
    model, w, rng = noisy_data(args.samples)
    half = with_gaps(w, 0.5, rng)
    half_outputs = np.hstack([w[:, :2], with_gaps(w[:, 2:], 0.5, rng)])
    tenth = with_gaps(w, 0.1, rng)
    record = {"T": args.samples, "machine": platform.processor() or platform.machine(), "cpus": os.cpu_count()}

    runs = [timed(lambda: ident(w, 2, 2, init="lra")) for _ in range(REPEATS)]
    seconds, (sysh, info, _, _) = min(runs, key=lambda run: run[1][1].time)
    record["complete"] = {"seconds": seconds, "iterations": info.iter, "solver_seconds": info.time,
                          "per_iteration": info.time / max(info.iter, 1)}
    seconds, (sysh_half, info_half, _, _) = timed(lambda: ident(half_outputs, 2, 2, init="lra"))
    kernel = in_chart(ss_to_kernel(sysh_half, 2))
    evaluations = {}
    for name, data in (("outputs", half_outputs), ("all", half)):
        values, weights = np.nan_to_num(data), np.where(np.isnan(data), 0.0, 1.0)
        evaluations[name] = timed(lambda: evaluation(kernel, values, weights, "normal"), REPEATS)[0]
        evaluations[name + "_jacobian"] = timed(lambda: evaluation(kernel, values, weights, "jacobian"), REPEATS)[0]
        evaluations[name + "_sparse"] = timed(lambda: sparse_solution(kernel, values, weights, jacobian=True))[0]
    record["missing_50"] = {"seconds": seconds, "iterations": info_half.iter, "message": info_half.message,
                            "per_iteration": evaluations["outputs"], "per_iteration_all": evaluations["all"],
                            "per_iteration_jacobian": evaluations["outputs_jacobian"],
                            "per_iteration_all_jacobian": evaluations["all_jacobian"],
                            "per_iteration_sparse": evaluations["outputs_sparse"],
                            "per_iteration_all_sparse": evaluations["all_sparse"]}
    record["per_iteration_ratio"] = evaluations["outputs"] / record["complete"]["per_iteration"]
    record["per_iteration_ratio_all"] = evaluations["all"] / record["complete"]["per_iteration"]
    record["per_iteration_ratio_jacobian"] = evaluations["outputs_jacobian"] / record["complete"]["per_iteration"]
    record["per_iteration_ratio_sparse"] = evaluations["outputs_sparse"] / record["complete"]["per_iteration"]
    record["total_ratio"] = record["missing_50"]["seconds"] / record["complete"]["seconds"]

    best, found = interleaved({"complete": lambda: misfit(w, sysh), "gram": lambda: misfit(tenth, sysh),
                               "banded_lu": lambda: without_gram(lambda: misfit(tenth, sysh))}, MISFIT_ROUNDS)
    complete_misfit, gappy_misfit, M = best["complete"], best["gram"], found["gram"][0]
    matrices = [np.asarray(getattr(sysh, x), dtype=float) for x in "ABCD"]
    smoother, smoothed = timed(lambda: smoothed_misfit(*matrices, [tenth], banded=False))
    kernel = in_chart(ss_to_kernel(sysh, 2))
    saddle, sparse = timed(lambda: sparse_solution(kernel, np.nan_to_num(tenth), np.where(np.isnan(tenth), 0.0, 1.0)))
    M_saddle = float(np.sum(sparse.residuals ** 2))
    record["misfit"] = {"complete": complete_misfit, "missing_10": gappy_misfit, "ratio": gappy_misfit / complete_misfit,
                        "rounds": MISFIT_ROUNDS, "banded_lu_missing_10": best["banded_lu"],
                        "banded_lu_ratio": best["banded_lu"] / complete_misfit,
                        "banded_lu_relative_difference": abs(M - found["banded_lu"][0]) / M,
                        "smoother_missing_10": smoother, "smoother_ratio": smoother / complete_misfit,
                        "saddle_point_missing_10": saddle, "saddle_point_ratio": saddle / complete_misfit,
                        "relative_difference": abs(M - M_saddle) / M,
                        "smoother_relative_difference": abs(M - smoothed.misfit) / M}
    record["memory"] = [peak_memory(size) for size in args.memory_sizes]
    record["evaluation_memory"] = [evaluation_memory(size, form) for form in ("normal", "jacobian")
                                   for size in args.evaluation_sizes]
    record["band"] = band_size(max(args.evaluation_sizes))
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(record, indent=1) + "\n")
    print(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
