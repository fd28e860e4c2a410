"""The DAISY runner's scaling curve: serial, then local Dask clusters of 2, 4, 8, 16 workers. Not a test.

Issue 30, deliverable 4: on a machine with 16 cores, 16 workers at least 5 times faster than serial;
report the curve. Each run is the whole benchmark (17 sets, both modes, ident's defaults, maxiter 500,
with the replays) as `python -m ident daisy [--workers N]` does it, timed whole: the cluster's start
and shutdown are inside its time, as a user waits for them. The files of every run are compared byte
for byte with the serial run's. Run it on a machine with that many cores; on fewer, the larger
clusters only share the cores.

Usage: python benchmarks/bench_daisy_scaling.py [--workers=2,4,8,16] [--sets=a,b] [--serial=SECONDS] [--out=FILE]
--serial=SECONDS skips the serial run (its time from an earlier run on the same kind of machine); the
files are then compared among the clusters' runs.
"""
import json
import os
import platform
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_daisy_workers import files_of, longest_job, one_run  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results" / "daisy_scaling.json"


def main(argv: list[str]) -> int:
    options = dict(a[2:].split("=", 1) for a in argv if a.startswith("--") and "=" in a)
    counts = [int(n) for n in options.get("workers", "2,4,8,16").split(",")]
    sets = options["sets"].split(",") if "sets" in options else None
    if "serial" in options:  # the serial time of an earlier run on this kind of machine: the files compare among clusters
        wall, results, serial_files = float(options["serial"]), None, None
        curve = {"1 (serial)": {"seconds": wall, "speed_up": 1.0, "given": True}}
    else:
        wall, results = one_run(None, sets)
        serial_files = files_of(results)
        curve = {"1 (serial)": {"seconds": wall, "speed_up": 1.0, "identical_files": True}}
    print(f"serial: {wall:.1f} s", flush=True)
    for n in counts:
        seconds, these = one_run(n, sets)
        files = files_of(these)
        serial_files = serial_files or files  # with a given serial time: the first cluster's files
        same = files == serial_files
        curve[str(n)] = {"seconds": seconds, "speed_up": wall / seconds, "identical_files": same}
        print(f"{n} workers: {seconds:.1f} s, {wall / seconds:.2f} x serial, files identical: {same}", flush=True)
    record = {"what": "DAISY Table 1 (sets: all 17 unless named), both modes, ident's defaults with the runner's "
                      "replays; wall seconds of one run each, the cluster's start and shutdown included",
              "sets": sets or "all of Table 1", "curve": curve, "longest_job_bound_seconds": longest_job(results) if results else None,
              "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                          "openblas_coretype": os.environ.get("OPENBLAS_CORETYPE", "native")}}
    Path(options.get("out", RESULTS)).write_text(json.dumps(record, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
