"""misfit(w, sysh) against ident's info.M on the 17 DAISY sets of Table 1, both modes.

    python benchmarks/misfit_daisy.py [--data-dir ../shared/daisy]

For each set: the first 70 % centred, ident with the lag of Table 1 (errors-in-variables, and output
error with the inputs exact, 60 iterations), then misfit of the returned model on the same data:
the relative difference from info.M, and how far the smoothed trajectory's own misfit
||w - wh||^2 (over the corrected variables) is from M. A few minutes (the identifications).
"""
from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from ident import daisy, ident, misfit


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-dir", default=None, help="folder of the DAISY files (default: ident.daisy's)")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    worst = 0.0
    print(f"{'set':18s} mode  n   info.M        misfit        relative  ||w-wh||^2 vs M  seconds")
    for entry in daisy.table1():
        u, y = daisy.load(entry.name, args.data_dir, download_missing=False)
        w = np.hstack([u, y])
        w = w[:int(0.7 * len(w))]
        w = w - w.mean(axis=0)
        for mode, exact in (("EIV", None), ("OE", list(range(entry.m)))):
            sysh, info, _, _ = ident(w, entry.m, entry.ell, exct=exact, maxiter=60)
            start = time.perf_counter()
            M, wh, _ = misfit(w, sysh, exct=exact)
            seconds = time.perf_counter() - start
            corrected = np.ones(w.shape[1], bool)
            corrected[exact or []] = False
            relative = abs(M - info.M) / info.M
            own = abs(np.sum((w - wh)[:, corrected] ** 2) - M) / M
            worst = max(worst, relative)
            print(f"{entry.name:18s} {mode:4s} {sysh.nstates:2d}  {info.M:12.6g}  {M:12.6g}  {relative:8.1e}  "
                  f"{own:15.1e}  {seconds:7.2f}")
    print(f"largest relative difference from info.M: {worst:.1e}")


if __name__ == "__main__":
    main()
