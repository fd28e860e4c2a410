"""Reproduce the paper's Section 4: ident on the 17 DAISY data sets of Table 1, both modes.

Writes docs/daisy/table.md, table.csv, results.json and figure1.png, and the run log run-log.json
(date, versions, seconds; not committed) beside them (the table in
literate/04-daisy.md is pasted from table.md). A thin wrapper of ``python -m ident daisy``: the
output folder defaults to docs/daisy, and the data to the shared folder beside the project when
IDENT_DAISY_DIR is not set. Any option of ``python -m ident daisy`` may be given.

Usage: python benchmarks/daisy_table.py [SET ...] [--starts lra] [--data-dir DIR] [--out FOLDER] ...
"""
import os
import sys
from pathlib import Path

from ident.cli import main

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "daisy"


def arguments(argv: list[str]) -> list[str]:
    args = list(argv)
    if "--out" not in args:
        args += ["--out", str(ROOT / "docs" / "daisy")]
    if "--data-dir" not in args and not os.environ.get("IDENT_DAISY_DIR") and SHARED.is_dir():
        args += ["--data-dir", str(SHARED)]
    return ["daisy", *args]


if __name__ == "__main__":
    sys.exit(main(arguments(sys.argv[1:])))
