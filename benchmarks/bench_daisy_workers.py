"""The DAISY runner serial against a local Dask cluster of 2 worker processes, side by side. Not a test.

Issue 30's bar: on this 2-core machine the cluster run takes at most 0.6 of the serial wall time, and
writes the same files byte for byte. Both runs do the whole benchmark (17 sets, both modes, ident's
defaults, maxiter 500) as ``python -m ident daisy [--workers 2]`` does: the cluster's start and
shutdown are inside its time, as a user waits for them. On the cluster the runner sends one job per
set, mode and replay (102 jobs) through ident.executors. The two alternate, round after round, and
the best of the rounds of each is kept; the files of both runs are compared byte for byte. The load
average before each run is recorded: a ratio measured while other work ran on the machine is not
the ratio of a quiet one (the other work takes a share of the two cores from the cluster's workers).
Writes benchmarks/results/daisy_workers.json, which 20-many-identifications.md reads.

Usage: python benchmarks/bench_daisy_workers.py [--rounds=2] [--workers=2] [--sets=erie,dryer] [--out=FILE]
"""
import concurrent.futures
import json
import multiprocessing
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

from ident import daisy_report, daisy_runner
from ident.batch import dask_executor

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "daisy"
RESULTS = ROOT / "benchmarks" / "results" / "daisy_workers.json"
BAR = 0.6  # issue 30: the 2-worker cluster at most 0.6 of the serial wall time


def one_run(workers: int | None, sets: list[str] | None):
    started = time.perf_counter()
    if workers is None:
        results = daisy_runner.run_benchmark(sets, directory=DATA, download_missing=False, progress=None)
    else:
        with dask_executor(workers=workers) as executor:
            results = daisy_runner.run_benchmark(sets, directory=DATA, download_missing=False, progress=None,
                                                 executor=executor)
    return time.perf_counter() - started, results


def files_of(results) -> dict[str, bytes]:
    with tempfile.TemporaryDirectory() as folder:
        paths = daisy_report.write_results(results, folder)
        return {key: Path(paths[key]).read_bytes() for key in ("markdown", "csv", "json", "figure")}


def longest_job(results) -> float:
    """A bound on the longest job of the cluster's run (one run of one set in one mode), from the serial
    run: the run's seconds, or its replays' together (ModeResult keeps their sum)."""
    return max(max(mode.seconds, mode.replay_seconds) for result in results for mode in result.modes.values())


def scaling_task(name: str, mode: str) -> float:
    """One run of a set in one mode (a job of the runner); its wall seconds where it ran."""
    info, split = daisy_runner.protocol_split(name, DATA, None, False)
    started = time.perf_counter()
    daisy_runner.mode_run(name, mode, 0, split.identification, split.validation, info.m, info.ell,
                          daisy_runner.benchmark_options())
    return time.perf_counter() - started


def machine_scaling(name: str = "pHdata", mode: str = "eiv", rounds: int = 2) -> dict:
    """What the machine's cores give at most: one job twice, one after the other in this process, against
    twice at once in two worker processes started (and warmed) before the clock. 0.5 for two whole cores."""
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        list(pool.map(scaling_task, [name, name], [mode, mode]))  # import and warm both workers
        scaling_task(name, mode)  # and this process
        one, two = [], []
        for _ in range(rounds):
            started = time.perf_counter()
            scaling_task(name, mode), scaling_task(name, mode)
            one.append(time.perf_counter() - started)
            started = time.perf_counter()
            list(pool.map(scaling_task, [name, name], [mode, mode]))
            two.append(time.perf_counter() - started)
    return {"task": [name, mode], "one_process_twice": min(one), "two_processes_at_once": min(two),
            "ratio": min(two) / min(one)}


def main(argv: list[str]) -> int:
    options = dict(a[2:].split("=", 1) for a in argv if a.startswith("--") and "=" in a)
    rounds, workers = int(options.get("rounds", 2)), int(options.get("workers", 2))
    sets = options["sets"].split(",") if "sets" in options else None  # a trial on a few sets; default all 17
    name = f"{workers} workers"
    seconds, loads, files, longest = {"serial": [], name: []}, {"serial": [], name: []}, {}, []
    for k in range(rounds):
        for n in ([None, workers] if k % 2 == 0 else [workers, None]):
            key = "serial" if n is None else name
            loads[key].append(os.getloadavg()[0])
            wall, results = one_run(n, sets)
            seconds[key].append(wall)
            if n is None:
                longest.append(longest_job(results))
            these = files_of(results)
            same = files.setdefault(key, these) == these
            print(f"round {k + 1} {key}: {wall:.1f} s (load average before {loads[key][-1]:.2f}; "
                  f"files as in its first round: {same})", flush=True)
    scaling = machine_scaling()
    print(f"two processes at once / one process twice: {scaling['ratio']:.2f}", flush=True)
    best = {key: min(values) for key, values in seconds.items()}
    record = {
        "what": "DAISY Table 1 (sets: all 17 unless named), both modes, ident's defaults; wall seconds including the cluster's "
                "start and shutdown; best of the rounds, alternating; one job per set, mode and replay",
        "bar": BAR, "rounds": rounds, "workers": workers, "sets": sets or "all of Table 1",
        "jobs": len(results) * len(daisy_runner.MODES) * (daisy_runner.REPLAYS + 1),
        "seconds": seconds, "best": best, "ratio": best[name] / best["serial"],
        "identical_files": files["serial"] == files[name],
        "longest_job_bound_seconds": longest[seconds["serial"].index(best["serial"])],
        "load_average_before": loads, "machine_scaling": scaling,
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
    }
    Path(options.get("out", RESULTS)).write_text(json.dumps(record, indent=1) + "\n")
    print(json.dumps(record, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
