"""Start-up time of ident against its floor, numpy + scipy.linalg (literate/10-representations.md,
"State-space models in python-control"; issue 17's bar: `import ident` within 1.5 times the floor).

    python benchmarks/bench_import.py [--rounds N] [--out benchmarks/bench_import.json]

Each measurement is a fresh interpreter (nothing cached in the process; the operating system's file
cache is warm after the first round). The candidates run alternately, round after round, so that a
change in the machine's load hits them alike, and the best of N rounds of each is kept: the best is
the run least disturbed by other work. Two measures:

- import: seconds spent in the import statement itself, timed inside the child with
  time.perf_counter() around it (the interpreter's own start-up, the same for all, is left out);
- wall: the whole child process, start to exit, for the command line (`python -m ident --help`),
  against a child that imports numpy and scipy.linalg and exits.

The ratios are reported, not the seconds alone, since the seconds depend on the machine and its load.
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

IMPORTS = {
    "numpy + scipy.linalg": "import numpy, scipy.linalg",
    "ident": "import ident",
    "ident + python-control": "import ident, control",
}
TIMED = "import time; t = time.perf_counter(); {statement}; print(time.perf_counter() - t)"
COMMANDS = {
    "python -c 'import numpy, scipy.linalg'": ["-c", "import numpy, scipy.linalg"],
    "python -m ident --help": ["-m", "ident", "--help"],
}


def import_seconds(statement: str) -> float:
    """Seconds of one import statement in a fresh interpreter."""
    out = subprocess.run([sys.executable, "-c", TIMED.format(statement=statement)], check=True,
                         capture_output=True, text=True).stdout
    return float(out.strip().splitlines()[-1])


def wall_seconds(arguments: list[str]) -> float:
    """Seconds from the start of a fresh interpreter running `arguments` to its exit."""
    start = time.perf_counter()
    subprocess.run([sys.executable, *arguments], check=True, capture_output=True)
    return time.perf_counter() - start


def measure(rounds: int) -> dict:
    imports = {name: [] for name in IMPORTS}
    walls = {name: [] for name in COMMANDS}
    for _ in range(rounds):  # alternating: every round runs each candidate once
        for name, statement in IMPORTS.items():
            imports[name].append(import_seconds(statement))
        for name, arguments in COMMANDS.items():
            walls[name].append(wall_seconds(arguments))
    best_import = {name: min(times) for name, times in imports.items()}
    best_wall = {name: min(times) for name, times in walls.items()}
    floor = best_import["numpy + scipy.linalg"]
    return {
        "rounds": rounds,
        "python": platform.python_version(),
        "best_import_seconds": best_import,
        "best_wall_seconds": best_wall,
        "ratio_import_ident": best_import["ident"] / floor,
        "ratio_import_ident_with_control": best_import["ident + python-control"] / floor,
        "ratio_wall_help": best_wall["python -m ident --help"] / best_wall["python -c 'import numpy, scipy.linalg'"],
        "load_average": [round(x, 2) for x in os.getloadavg()],
        "note": "best of the rounds, candidates alternating; the machine may have been shared (load_average)",
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=15, help="rounds (each candidate once per round)")
    parser.add_argument("--out", type=Path, help="write the results as JSON here")
    args = parser.parse_args()
    result = measure(args.rounds)
    for name, seconds in result["best_import_seconds"].items():
        print(f"import {name:24s} {seconds:.3f} s (best of {args.rounds})")
    for name, seconds in result["best_wall_seconds"].items():
        print(f"{name:40s} {seconds:.3f} s wall (best of {args.rounds})")
    print(f"import ident / import numpy, scipy.linalg = {result['ratio_import_ident']:.2f} (bar: 1.5)")
    print(f"python -m ident --help / python -c 'import numpy, scipy.linalg' = {result['ratio_wall_help']:.2f}")
    print(f"with python-control loaded too: {result['ratio_import_ident_with_control']:.2f}")
    if args.out:
        args.out.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
