"""The DAISY runner serial against a local Dask cluster of 2 worker processes, side by side. Not a test.

Issue 18's bar: on this 2-core machine the cluster run takes at most 0.75 of the serial wall time.
Both runs do the whole benchmark (17 sets, both modes, ident's defaults, maxiter 500) in this
process's caller's sense: the cluster's start and shutdown are inside its time, as a user of
``python -m ident daisy --workers 2`` waits for them. The two alternate, round after round, and the
best of the rounds of each is kept; the files of both runs are compared byte for byte. Writes
benchmarks/bench_daisy_workers.json, which 15-many-identifications.md reads.

Usage: python benchmarks/bench_daisy_workers.py [--rounds=2] [--workers=2]
"""
import json
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


def one_run(workers: int | None):
    started = time.perf_counter()
    if workers is None:
        results = daisy_runner.run_benchmark(directory=DATA, download_missing=False, progress=None)
    else:
        with dask_executor(workers=workers) as executor:
            results = daisy_runner.run_benchmark(directory=DATA, download_missing=False, progress=None,
                                                 executor=executor)
    return time.perf_counter() - started, results


def files_of(results) -> dict[str, bytes]:
    with tempfile.TemporaryDirectory() as folder:
        paths = daisy_report.write_results(results, folder)
        return {key: Path(paths[key]).read_bytes() for key in ("markdown", "csv", "json", "figure")}


def main(argv: list[str]) -> int:
    options = dict(a[2:].split("=", 1) for a in argv if a.startswith("--") and "=" in a)
    rounds, workers = int(options.get("rounds", 2)), int(options.get("workers", 2))
    load = os.getloadavg()
    seconds = {"serial": [], f"{workers} workers": []}
    files = {}
    for k in range(rounds):
        order = [None, workers] if k % 2 == 0 else [workers, None]
        for n in order:
            wall, results = one_run(n)
            name = "serial" if n is None else f"{workers} workers"
            seconds[name].append(wall)
            files.setdefault(name, files_of(results))
            print(f"round {k + 1} {name}: {wall:.1f} s", flush=True)
    best = {name: min(values) for name, values in seconds.items()}
    record = {
        "what": "DAISY Table 1, 17 sets, both modes, ident's defaults; wall seconds including the cluster's "
                "start and shutdown; best of the rounds, alternating",
        "rounds": rounds, "workers": workers, "seconds": seconds, "best": best,
        "ratio": best[f"{workers} workers"] / best["serial"],
        "identical_files": files["serial"] == files[f"{workers} workers"],
        "machine": {"cpus": os.cpu_count(), "load_average_at_start": load, "load_average_at_end": os.getloadavg(),
                    "python": platform.python_version()},
    }
    (ROOT / "benchmarks" / "bench_daisy_workers.json").write_text(json.dumps(record, indent=1) + "\n")
    print(json.dumps(record, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
