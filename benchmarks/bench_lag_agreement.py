"""The command line's `lag SET` and the API's choose_lag choose the same lag on every DAISY set. Not a test.

Issue 31's acceptance: with the defaults of `python -m ident lag` (lags 1-8, both modes, holdout 0.3,
offset "mean", maxiter 100) and the documented equivalent call of the API (choose_lag on the
identification part the command line centres and splits, with the lags of the range it can judge
there, lag_refusal, and the same exact variables),
the chosen lag of every set and mode is printed side by side and written to
benchmarks/bench_lag_agreement.json. tests/test_cli.py runs the same comparison on lags 1-3 with 20
iterations (marked slow); this is the whole range at the defaults (minutes per set).

Usage: python benchmarks/bench_lag_agreement.py [SET ...] [--processes N]
"""
import argparse
import contextlib
import io
import json
import multiprocessing
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

from ident import cli, daisy, daisy_runner
from ident.lag_arguments import CHOOSE_LAG_HOLDOUT, lag_refusal
from ident.validation import choose_lag, split_for_validation

ROOT = Path(__file__).resolve().parents[1]
DAISY = ROOT.parent / "shared" / "daisy"
LAGS = list(range(1, 9))  # the command line's default --lags 1-8
TABLE1_SETS = [dataset.name for dataset in daisy.table1()]


def command_line_choices(name: str) -> dict[str, str]:
    """mode -> the chosen lag `python -m ident lag NAME` prints (or its "no lag chosen" reason)."""
    printed = io.StringIO()
    with tempfile.TemporaryDirectory() as folder, contextlib.redirect_stdout(printed):
        status = cli.main(["lag", name, "--data-dir", str(DAISY), "--no-download", "--plot", f"{folder}/lag.png"])
    if status != 0:
        raise RuntimeError(f"lag {name} exited with status {status}")
    choices = {}
    for mode in ("OE", "EIV"):
        line = next(line for line in printed.getvalue().splitlines()
                    if line.startswith((f"chosen lag ({mode}, ", f"no lag chosen ({mode})")))
        choices[mode] = line.split(": ")[1].split()[0] if line.startswith("chosen") else "none"
    return choices


def api_choices(name: str) -> dict[str, str]:
    """mode -> choose_lag's lag on the identification part, with the command line's exact variables,
    among the lags it can judge there (lag_refusal None), as the command line chooses."""
    info = daisy.dataset(name)
    u, y = daisy.load(name, DAISY, download_missing=False)
    w = split_for_validation(u, y, daisy_runner.HOLDOUT).identification
    choices = {}
    for mode, exct in (("OE", list(range(info.m))), ("EIV", None)):
        try:
            judged = [lag for lag in LAGS if lag_refusal(w, info.m, lag, CHOOSE_LAG_HOLDOUT) is None]
            choices[mode] = str(choose_lag(w, info.m, judged, exct=exct).ell)
        except ValueError:
            choices[mode] = "none"
    return choices


def set_rows(name: str) -> list[dict]:
    """Both ways on one set: a row per mode."""
    warnings.simplefilter("ignore")
    started = time.perf_counter()
    from_cli, from_api = command_line_choices(name), api_choices(name)
    seconds = time.perf_counter() - started
    rows = [{"set": name, "mode": mode, "command_line": from_cli[mode], "api": from_api[mode],
             "same": from_cli[mode] == from_api[mode]} for mode in ("OE", "EIV")]
    for row in rows:
        print(f"{name:18s} {row['mode']:3s} lag: command line {row['command_line']:>4s}, choose_lag {row['api']:>4s}"
              f"{'' if row['same'] else '   DIFFERENT'}  ({seconds:.0f} s for both modes and both ways)", flush=True)
    return rows


def main(names: list[str], processes: int) -> int:
    with multiprocessing.Pool(processes) as pool:  # one set per task, the largest last in the list
        rows = [row for set_result in pool.map(set_rows, names, chunksize=1) for row in set_result]
    agree = sum(row["same"] for row in rows)
    print(f"the same lag in {agree} of {len(rows)} (set, mode) pairs")
    if sorted(names) == sorted(TABLE1_SETS):
        out = ROOT / "benchmarks" / "bench_lag_agreement.json"
        out.write_text(json.dumps({"lags": LAGS, "rows": rows, "same": agree, "pairs": len(rows)}, indent=1) + "\n")
        print(f"wrote {out}")
    return 0 if agree == len(rows) else 1


if __name__ == "__main__":
    arguments = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    arguments.add_argument("sets", nargs="*", help="DAISY sets (default: the 17 of Table 1)")
    arguments.add_argument("--processes", type=int, default=os.cpu_count(), help="sets run at once")
    options = arguments.parse_args()
    sys.exit(main(options.sets or list(TABLE1_SETS), options.processes))
