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
benchmarks/bench_batch.json (read by literate/04b-many-identifications.md). Timings on a machine
shared with other work are noisy: the runs are side by side in one process so that their ratio is
fair, and the load average is recorded.

Usage: python benchmarks/bench_batch.py [--data-dir DIR] [--workers N] [--process-pool] [--dask-defaults]
                                        [--out FILE]
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

from ident import Job, dask_executor, daisy, run_jobs
from ident.batch import ONE_THREAD

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "daisy"


def daisy_jobs(directory) -> list[Job]:
    """Both modes of every set of Table 1, from the paper's start and from the least-squares kernel."""
    jobs = []
    for info in daisy.table1():
        u, y = daisy.load(info.name, directory, download_missing=False)
        w_identification, _ = daisy.split_centred(u, y)
        starts = {"lra": None, "arx": daisy.least_squares_kernel(w_identification, info.m, info.ell)}
        for mode, exact in (("oe", list(range(info.m))), ("eiv", None)):
            for start, kernel in starts.items():
                jobs.append(Job(w_identification, info.m, info.ell,
                                {"exct": exact, "sys0": kernel, **daisy.SETTINGS}, label=(info.name, mode, start)))
    return jobs


def timed(label: str, run) -> tuple[list, float]:
    print(f"{label} ...", end=" ", flush=True)
    started = time.perf_counter()
    results = run()
    wall = time.perf_counter() - started
    print(f"{wall:.1f} s", flush=True)
    return results, wall


def machine() -> str:
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (f"{os.cpu_count()} cores ({platform.machine()}), Python {platform.python_version()}, numpy "
            f"{np.__version__}, load average {load:.1f} when the run started (shared with other work)")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data-dir", default=os.environ.get("IDENT_DAISY_DIR") or SHARED)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--process-pool", action="store_true", help="also run in a ProcessPoolExecutor")
    parser.add_argument("--dask-defaults", action="store_true",
                        help="also run on a local cluster with Dask's worker environment (MALLOC_TRIM_THRESHOLD_)")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "bench_batch.json")
    args = parser.parse_args(argv)
    where = machine()
    jobs = daisy_jobs(args.data_dir)
    print(f"{len(jobs)} jobs (DAISY Table 1, both modes, starts lra and arx); {where}")
    warnings.simplefilter("ignore")  # non-convergence is in each result's info
    runs = {}
    serial, wall = timed("serial", lambda: run_jobs(jobs))
    runs["serial"] = {"wall": wall, "sum_of_job_seconds": sum(r.seconds for r in serial)}
    outcomes, cluster_start = {}, []

    def on_dask():
        started = time.perf_counter()
        with dask_executor(workers=args.workers) as executor:
            cluster_start.append(time.perf_counter() - started)
            return run_jobs(jobs, executor)

    name = f"dask, {args.workers} workers"
    outcomes[name], wall = timed(name, on_dask)
    runs[name] = {"wall": wall, "cluster_start": cluster_start[0],
                  "sum_of_job_seconds": sum(r.seconds for r in outcomes[name])}
    if args.dask_defaults:
        name = f"dask defaults, {args.workers} workers"

        def on_dask_defaults():  # as dask_executor, but with Dask's MALLOC_TRIM_THRESHOLD_=65536 kept
            import distributed

            with distributed.LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                                          dashboard_address=None, env=ONE_THREAD) as cluster:
                with distributed.Client(cluster) as client:
                    return run_jobs(jobs, client.get_executor(pure=False))

        outcomes[name], wall = timed(name, on_dask_defaults)
        runs[name] = {"wall": wall, "sum_of_job_seconds": sum(r.seconds for r in outcomes[name])}
    if args.process_pool:
        name = f"process pool, {args.workers} processes"
        context = multiprocessing.get_context("spawn")

        def in_pool():
            with concurrent.futures.ProcessPoolExecutor(args.workers, mp_context=context) as pool:
                return run_jobs(jobs, pool)

        outcomes[name], wall = timed(name, in_pool)
        runs[name] = {"wall": wall, "sum_of_job_seconds": sum(r.seconds for r in outcomes[name])}
    identical = all(a.identical_to(b) for results in outcomes.values() for a, b in zip(serial, results))
    failed = [r.job.label for r in serial if not r.ok]
    print(f"identical to the serial run: {identical}; failed jobs: {failed or 'none'}")
    for name, run in runs.items():
        print(f"  {name:28s} wall {run['wall']:6.1f} s  ratio to serial {run['wall'] / runs['serial']['wall']:.2f}"
              + (f"  (cluster start {run['cluster_start']:.1f} s)" if "cluster_start" in run else ""))
    document = {"generated": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
                "command": "python benchmarks/bench_batch.py " + " ".join(argv if argv is not None else sys.argv[1:]),
                "machine": where, "n_jobs": len(jobs), "failed_jobs": [list(label) for label in failed],
                "identical": identical, "runs": runs,
                "serial_jobs": [{"label": list(r.job.label), "size": r.job.size, "seconds": r.seconds} for r in serial]}
    args.out.write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {args.out}")
    return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())
