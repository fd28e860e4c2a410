"""What Dask's worker setting MALLOC_TRIM_THRESHOLD_=65536 costs ident's jobs.

Dask starts its worker processes with MALLOC_TRIM_THRESHOLD_=65536 (distributed's
`distributed.nanny.pre-spawn-environ`), so that glibc returns freed memory to the system at once;
`ident.dask_executor` leaves it out. This script runs the same DAISY jobs as bench_batch.py (or the
sets named on the command line) serially in fresh processes, alternately without and with the
setting, and prints the processor time of the jobs (their threads' CPU time, which other work on
the machine disturbs less than wall time) and its ratio.

Usage: python benchmarks/bench_malloc_trim.py [--rounds N] [SET ...]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent


def child(names: list[str]) -> None:
    """Run the jobs of the named sets here and print their processor time as JSON."""
    sys.path.insert(0, str(HERE))
    from bench_batch import SHARED, daisy_jobs

    from ident import run_jobs

    warnings.simplefilter("ignore")
    jobs = [job for job in daisy_jobs(os.environ.get("IDENT_DAISY_DIR") or SHARED)
            if not names or job.label[0] in names]
    results = run_jobs(jobs)
    print(json.dumps({"cpu_seconds": sum(r.cpu_seconds for r in results),
                      "wall_seconds": sum(r.seconds for r in results), "n_jobs": len(jobs)}))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("sets", nargs="*", help="DAISY sets (default: all 17)")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.sets)
        return 0
    times = {"glibc default": [], "MALLOC_TRIM_THRESHOLD_=65536": []}
    for k in range(args.rounds):
        for setting in times:
            env = {key: value for key, value in os.environ.items() if key != "MALLOC_TRIM_THRESHOLD_"}
            env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
            if setting != "glibc default":
                env["MALLOC_TRIM_THRESHOLD_"] = "65536"
            out = subprocess.run([sys.executable, __file__, "--child", *args.sets], env=env, check=True,
                                 capture_output=True, text=True).stdout
            measured = json.loads(out.strip().splitlines()[-1])
            times[setting].append(measured["cpu_seconds"])
            print(f"round {k + 1}, {setting}: {measured['n_jobs']} jobs, processor time {measured['cpu_seconds']:.1f} s "
                  f"(wall {measured['wall_seconds']:.1f} s), load average {os.getloadavg()[0]:.1f}", flush=True)
    default, trimmed = times.values()
    ratios = [b / a for a, b in zip(default, trimmed)]
    print("processor time with the setting / without: " + ", ".join(f"{r:.2f}" for r in ratios))
    return 0


if __name__ == "__main__":
    sys.exit(main())
