"""Many identifications serially and on a local Dask cluster, side by side in one run.

The jobs are the identifications of the DAISY benchmark (literate/04-daisy.md), called through
`ident` directly with the paper's protocol: the 17 data sets of Table 1, centred, the first 70 %
identifying, in both modes (output error, errors-in-variables), from the paper's start (`lra`)
and from the least-squares kernel (`arx`), maxiter 500, tol 1e-5: 68 jobs. They run

1. serially, in this process (`run_jobs(jobs)`),
2. on a local Dask cluster of `--workers` processes (default 2; the start of the cluster is
   included in the wall time and also reported alone),
3. optionally (`--process-pool`) in a `ProcessPoolExecutor` of as many processes,
4. optionally (`--dask-defaults`) on a local cluster as Dask starts it, with its worker environment
   `MALLOC_TRIM_THRESHOLD_=65536` that `dask_executor` leaves out,

and the script checks that every result is bit for bit the result of the serial run, prints the
times and their ratio, and writes them, with every job's size and time in the serial run, to
benchmarks/bench_batch.json (read by literate/20-many-identifications.md). Timings on a machine
shared with other work are noisy: the runs are side by side in one process so that their ratio is
fair, `--rounds N` repeats all of them in turn (the ratios of every round and their median are
written), and the load average is recorded before each round; each job's processor time is written
beside its wall time, so that a busy machine shows as wall time far above processor time, and so is
the processor time of the busiest worker: on an otherwise idle machine the run could not finish
sooner than that.

Usage: python benchmarks/bench_batch.py [--data-dir DIR] [--workers N] [--rounds N] [--process-pool]
                                        [--dask-defaults] [--out FILE]
"""
from __future__ import annotations

import argparse
import concurrent.futures
import datetime
import json
import multiprocessing
import os
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from ident import Job, daisy, daisy_runner, dask_executor, run_jobs
from ident.batch import ONE_THREAD
from ident.validation import split_for_validation

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "daisy"


def daisy_jobs(directory) -> list[Job]:
    """Both modes of every set of Table 1, from the paper's start and from the least-squares kernel."""
    jobs = []
    for info in daisy.table1():
        u, y = daisy.load(info.name, directory, download_missing=False)
        w_identification = split_for_validation(u, y, daisy_runner.HOLDOUT).identification
        starts = {"lra": None, "arx": daisy_runner.arx_kernel(w_identification, info.m, info.ell)}
        for mode, exact in (("oe", list(range(info.m))), ("eiv", None)):
            for start, kernel in starts.items():
                jobs.append(Job(w_identification, info.m, info.ell, {"exct": exact, "sys0": kernel,
                                                                     **daisy_runner.SETTINGS},
                                label=(info.name, mode, start)))
    return jobs


def variants(args) -> dict:
    """name -> function(jobs) returning (results, seconds to start the executor)."""

    def serial(jobs):
        return run_jobs(jobs), 0.0

    def on_dask(jobs):
        started = time.perf_counter()
        with dask_executor(workers=args.workers) as executor:
            start = time.perf_counter() - started
            return run_jobs(jobs, executor), start

    def on_dask_defaults(jobs):  # as dask_executor, but with Dask's MALLOC_TRIM_THRESHOLD_=65536 kept
        import distributed

        started = time.perf_counter()
        with distributed.LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                                      dashboard_address=None, env=ONE_THREAD) as cluster:
            with distributed.Client(cluster) as client:
                start = time.perf_counter() - started
                return run_jobs(jobs, client.get_executor(pure=False)), start

    def in_pool(jobs):
        started = time.perf_counter()
        with concurrent.futures.ProcessPoolExecutor(args.workers, mp_context=multiprocessing.get_context("spawn")) \
                as pool:
            start = time.perf_counter() - started
            return run_jobs(jobs, pool), start

    chosen = {"serial": serial, f"dask, {args.workers} workers": on_dask}
    if args.dask_defaults:
        chosen[f"dask defaults, {args.workers} workers"] = on_dask_defaults
    if args.process_pool:
        chosen[f"process pool, {args.workers} processes"] = in_pool
    return chosen


def measured(name: str, run, jobs) -> tuple[list, dict]:
    print(f"  {name} ...", end=" ", flush=True)
    started = time.perf_counter()
    results, start = run(jobs)
    wall = time.perf_counter() - started
    print(f"{wall:.1f} s", flush=True)
    busy = {}
    for result in results:
        busy[result.worker] = busy.get(result.worker, 0.0) + result.cpu_seconds
    return results, {"wall": wall, "start": start, "sum_of_job_seconds": sum(r.seconds for r in results),
                     "sum_of_job_cpu_seconds": sum(r.cpu_seconds for r in results),
                     "busiest_worker_cpu_seconds": max(busy.values())}


def machine() -> str:
    return f"{os.cpu_count()} cores ({platform.machine()}), Python {platform.python_version()}, numpy {np.__version__}"


def load_average() -> float:
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=os.environ.get("IDENT_DAISY_DIR") or SHARED)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=1, help="rounds of all variants, one after another")
    parser.add_argument("--process-pool", action="store_true", help="also run in a ProcessPoolExecutor")
    parser.add_argument("--dask-defaults", action="store_true",
                        help="also run on a local cluster with Dask's worker environment (MALLOC_TRIM_THRESHOLD_)")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "bench_batch.json")
    args = parser.parse_args(argv)
    jobs = daisy_jobs(args.data_dir)
    print(f"{len(jobs)} jobs (DAISY Table 1, both modes, starts lra and arx); {machine()}")
    warnings.simplefilter("ignore")  # non-convergence is in each result's info
    rounds, serial, identical = [], None, True
    for k in range(args.rounds):
        print(f"round {k + 1} of {args.rounds}, load average {load_average():.1f}")
        times = {"load_average_before": load_average()}
        for name, run in variants(args).items():
            results, times[name] = measured(name, run, jobs)
            serial = serial or results
            identical = identical and all(a.identical_to(b) for a, b in zip(serial, results))
        rounds.append(times)
    names = [name for name in rounds[0] if name not in ("serial", "load_average_before")]
    ratios = {name: [r[name]["wall"] / r["serial"]["wall"] for r in rounds] for name in names}
    failed = [r.job.label for r in serial if not r.ok]
    print(f"identical to the first serial run: {identical}; failed jobs: {failed or 'none'}")
    for name, values in ratios.items():
        print(f"  {name:28s} wall / serial wall: {', '.join(f'{v:.2f}' for v in values)} "
              f"(median {np.median(values):.2f})")
    document = {"generated": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
                "command": "python benchmarks/bench_batch.py " + " ".join(argv if argv is not None else sys.argv[1:]),
                "machine": machine(), "n_jobs": len(jobs), "failed_jobs": [list(label) for label in failed],
                "identical": identical, "rounds": rounds, "ratios": ratios,
                "median_ratio": {name: float(np.median(values)) for name, values in ratios.items()},
                "serial_jobs": [{"label": list(r.job.label), "size": r.job.size, "seconds": r.seconds,
                                 "cpu_seconds": r.cpu_seconds} for r in serial]}
    args.out.write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {args.out}")
    return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())
