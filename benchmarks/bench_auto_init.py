"""ident's defaults (init="auto") on DAISY, both modes, 17 sets: this checkout against an older one, side by side. Not a test.

Issue 30's bar: the identification time of DAISY, both modes, all 17 sets with `init="auto"`, at
most 0.5 of 497a486's, with the mean validation fits no lower and no set worse by more than 0.5 point.
Each version runs in its own fresh process (PYTHONPATH = that checkout's src/), the versions
alternating round after round with their order swapped; each call is timed whole, as a user waits:
`ident(w, m, ell, exct=..., init="auto", maxiter=500)` on the identification part of each set (OE:
the inputs exact; EIV: none), at each version's default tolerance. The best of the rounds is kept
per set and mode. Both versions get the same arrays (the parent splits the data with this
checkout's protocol and hands them over in a file), and both models are validated here, by this
checkout's `validate` on the validation part, so that the fits compare.

Usage: python benchmarks/bench_auto_init.py OLD_ROOT [--rounds=3] [--parallel=N] [--sets=a,b] [--json=FILE]
--parallel=N runs N worker processes at once (a round's two versions and several rounds), for a machine
with cores to spare; 1 (the default) runs them one after another.
"""
import concurrent.futures
import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DAISY = HERE.parents[1] / "shared" / "daisy"
RESULTS = HERE / "results" / "auto_init.json"
BAR = 0.5


def worker(arrays: str) -> None:
    """In a version's process: ident on every (set, mode) of the file; the times and models as JSON."""
    import control  # noqa: F401  imported before the clock starts
    from ident import ident
    data = np.load(arrays)
    out = {}
    for key in sorted({k.rsplit("/", 1)[0] for k in data.files}):
        w, (m, ell) = data[key + "/w"], data[key + "/shape"]
        mode = key.rsplit(":", 1)[1]
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            started = time.perf_counter()
            model, info, _, _ = ident(w, int(m), int(ell), exct=list(range(int(m))) if mode == "oe" else None,
                                      init="auto", maxiter=500)
            seconds = time.perf_counter() - started
        out[key] = {"seconds": seconds, "misfit": float(info.M), "start": str(getattr(info, "start", "")),
                    "A": np.asarray(model.A).tolist(), "B": np.asarray(model.B).tolist(),
                    "C": np.asarray(model.C).tolist(), "D": np.asarray(model.D).tolist()}
    print(json.dumps(out))


def split_arrays(sets, path: Path) -> dict:
    from ident import daisy
    from ident.daisy_runner import protocol_split
    arrays, validation = {}, {}
    for info in daisy.table1():
        if sets and info.name not in sets:
            continue
        entry, split = protocol_split(info.name, DAISY, None, False)
        for mode in ("oe", "eiv"):
            arrays[f"{info.name}:{mode}/w"] = split.identification
            arrays[f"{info.name}:{mode}/shape"] = np.array([entry.m, entry.ell])
        validation[info.name] = (split.validation, entry.m)
    np.savez(path, **arrays)
    return validation


def run_version(root: str, arrays: Path) -> dict:
    env = {**os.environ, "PYTHONPATH": str(Path(root) / "src")}
    done = subprocess.run([sys.executable, __file__, "--worker", str(arrays)], env=env, capture_output=True,
                          text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def fit_of(run: dict, validation) -> float:
    from ident.representations import make_ss
    from ident.validation import validate
    w_validation, m = validation
    D = np.array(run["D"], dtype=float)
    n = len(run["A"])
    model = make_ss(np.array(run["A"], dtype=float).reshape(n, n), np.array(run["B"], dtype=float).reshape(n, m),
                    np.array(run["C"], dtype=float).reshape(len(D), n), D, 1)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        return float(validate(model, w_validation[:, :m], w_validation[:, m:]).mean_fit)


def main(argv) -> None:
    options = dict(a.lstrip("-").split("=", 1) for a in argv if a.startswith("--") and "=" in a)
    old_root = next(a for a in argv if not a.startswith("--"))
    new_root = str(HERE.parent)
    rounds, parallel = int(options.get("rounds", 3)), int(options.get("parallel", 1))
    sets = options["sets"].split(",") if "sets" in options else None
    with tempfile.TemporaryDirectory() as folder:
        arrays = Path(folder) / "daisy.npz"
        validation = split_arrays(sets, arrays)
        order = []
        for r in range(rounds):
            pair = [("old", old_root), ("new", new_root)]
            order += pair if r % 2 == 0 else pair[::-1]
        started = time.perf_counter()
        with concurrent.futures.ThreadPoolExecutor(parallel) as pool:
            runs = list(pool.map(lambda job: (job[0], run_version(job[1], arrays)), order))
        wall = time.perf_counter() - started
    best = {"old": {}, "new": {}}
    for version, run in runs:
        for key, one in run.items():
            if key not in best[version] or one["seconds"] < best[version][key]["seconds"]:
                best[version][key] = one
    table, totals = {}, {"old": 0.0, "new": 0.0}
    for key in sorted(best["new"]):
        name, mode = key.split(":")
        row = {}
        for version in ("old", "new"):
            one = best[version][key]
            row[version] = {"seconds": one["seconds"], "misfit": one["misfit"], "start": one["start"],
                            "fit": fit_of(one, validation[name])}
            totals[version] += one["seconds"]
        row["fit_change"] = row["new"]["fit"] - row["old"]["fit"]
        table[key] = row
    means = {version: {mode: float(np.mean([table[k][version]["fit"] for k in table if k.endswith(":" + mode)]))
                       for mode in ("oe", "eiv")} for version in ("old", "new")}
    worst = min(table, key=lambda k: table[k]["fit_change"])
    out = {"old_root": old_root, "rounds": rounds, "parallel": parallel, "wall": wall,
           "openblas_coretype": os.environ.get("OPENBLAS_CORETYPE", "native"), "cpu_count": os.cpu_count(),
           "seconds": totals, "ratio": totals["new"] / totals["old"], "bar": BAR, "means": means,
           "worst_set": [worst, table[worst]["fit_change"]], "sets": table}
    print(f"init='auto', both modes, {len(table) // 2} sets: new {totals['new']:.2f} s, old {totals['old']:.2f} s, "
          f"ratio {out['ratio']:.3f} (bar {BAR}); mean fits OE {means['new']['oe']:.2f} / {means['old']['oe']:.2f}, "
          f"EIV {means['new']['eiv']:.2f} / {means['old']['eiv']:.2f}; worst change {worst} "
          f"{table[worst]['fit_change']:+.2f} points")
    path = Path(options.get("json", RESULTS))
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    if sys.argv[1:2] == ["--worker"]:
        worker(sys.argv[2])
    else:
        main(sys.argv[1:])
