"""The complexity found from the DAISY data sets of Table 1, against Table 1's (m, ell). Not a test.

For each of the 17 sets (the whole record, centred, inputs first): complexity(w) at its default
tolerance (the exact rule; noisy data give every variable free or a ValueError) and
complexity(w, noisy=True) (the order from the canonical correlations between past and future).
Writes benchmarks/results/complexity_daisy.json. Takes about a minute.

Usage: python benchmarks/complexity_daisy.py [DATA_DIR]   (default ../shared/daisy)
"""
import json
import sys
import time
from pathlib import Path

import numpy as np

from ident import complexity
from ident.daisy import load, table1


def main(argv):
    directory = argv[0] if argv else str(Path(__file__).resolve().parents[1].parent / "shared" / "daisy")
    rows = []
    for info in table1():
        u, y = load(info.name, directory, download_missing=False)
        w = np.hstack([u, y])
        w = w - w.mean(axis=0)
        started = time.perf_counter()
        row = {"name": info.name, "T": len(w), "m": info.m, "p": info.p, "ell": info.ell}
        try:
            exact = complexity(w)
            row["exact"] = {"m": exact.m, "ell": exact.ell, "n": exact.n}
        except ValueError as error:
            row["exact"] = {"error": str(error).split(":")[0]}
        try:
            noisy = complexity(w, noisy=True)
            row["noisy"] = {"m": noisy.m, "ell": noisy.ell, "n": noisy.n, "lags": list(noisy.lags),
                            "counts": list(noisy.ranks)}
        except ValueError as error:
            row["noisy"] = {"error": str(error).split(":")[0]}
        row["seconds"] = round(time.perf_counter() - started, 2)
        rows.append(row)
        print(row)
    out = Path(__file__).resolve().parent / "results" / "complexity_daisy.json"
    out.write_text(json.dumps({"benchmark": "benchmarks/complexity_daisy.py", "sets": rows}, indent=1) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1:])
