"""The time of the DAISY benchmark with ident's defaults: all 17 sets of Table 1, both modes. Not a test.

Runs ``ident.daisy_runner.run_benchmark`` (init "auto": the three starts and the rule of
08-identification) ``--rounds`` times in this process and keeps the best round: wall seconds of the
whole run, and ident's seconds per mode summed over the sets. The original software's seconds per
set (errors-in-variables, reference/README.md) are summed for the ratio. Writes
benchmarks/daisy_time.json, which 04-daisy.md reads.

Usage: python benchmarks/daisy_time.py [--rounds=2]
"""
import json
import os
import platform
import re
import sys
import time
from pathlib import Path

from ident import daisy_runner

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"


def original_eiv_seconds() -> float:
    """Sum of the seconds column of the original software's DAISY table (errors-in-variables)."""
    text = (ROOT / "reference" / "README.md").read_text()
    rows = re.findall(r"^\| \d+ \| \w+ \| [^|]+ \| [^|]+ \| ([0-9.]+) \|$", text, flags=re.M)
    return sum(float(x) for x in rows)


def one_round() -> dict:
    started = time.perf_counter()
    results = daisy_runner.run_benchmark(directory=SHARED / "daisy", download_missing=False, progress=None)
    wall = time.perf_counter() - started
    per_mode = {mode: sum(r.modes[mode].seconds for r in results) for mode in daisy_runner.MODES}
    return {"wall_seconds": wall, "ident_seconds": per_mode}


def main(argv: list[str]) -> int:
    rounds = int(next((a.split("=", 1)[1] for a in argv if a.startswith("--rounds=")), 2))
    load = os.getloadavg()
    measured = [one_round() for _ in range(rounds)]
    best = min(measured, key=lambda r: r["wall_seconds"])
    record = {
        "what": "DAISY Table 1, 17 sets, both modes, ident's defaults (init 'auto'), maxiter 500; best of rounds",
        "rounds": rounds, "best": best, "all_wall_seconds": [r["wall_seconds"] for r in measured],
        "original_eiv_seconds": original_eiv_seconds(),
        "machine": {"processor": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
                    "load_average_at_start": load, "python": platform.python_version()},
    }
    (ROOT / "benchmarks" / "daisy_time.json").write_text(json.dumps(record, indent=1) + "\n")
    print(json.dumps(record, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
