"""Record the numbers a refactoring must keep, to compare two versions bitwise. Not a test.

Records DAISY Table 1 by the runner with the paper's single start and with its default starts (both
modes, every candidate; before issue 13 the runner's three starts lra, arx, eiv, since then ident's
init="auto"), the solver alone on the Table 1 protocol (benchmarks/daisy_solver.py: EIV,
maxiter 100), and the misfits and iterations found in the namespaces of the examples of every
literate document. Floats are stored as float.hex. Run it on two checkouts and compare:

    python benchmarks/behaviour_record.py ROOT OUT.json [examples] [solver] [runner]
    python benchmarks/behaviour_record.py --compare BEFORE.json AFTER.json

ROOT is the project checkout whose src/ is imported; the DAISY files are read from ../shared/daisy
beside the project this script belongs to. About a minute and a half on the development machine.
"""
import json
import math
import os
import sys
import warnings
from pathlib import Path

DAISY = Path(__file__).resolve().parents[2] / "shared" / "daisy"
SETS = ["erie", "destill", "heating_system", "dryer2", "dryer", "ballbeam", "flutter", "robot_arm",
        "glassfurnace", "thermic_res_wall", "pHdata", "CD_player_arm", "winding", "exchanger",
        "evaporator", "cstr", "steamgen"]


def setup(root):
    """Import ident from the checkout `root`."""
    sys.path.insert(0, str(root / "src"))
    sys.path.insert(0, str(root))
    os.chdir(root)
    import matplotlib
    matplotlib.use("Agg")


def h(x):
    return float(x).hex()


def runner():
    try:
        from ident.daisy_runner import run_set
    except ImportError:  # before the DAISY modules were split
        from ident.daisy import run_set
    import inspect
    with_init = "init" in inspect.signature(run_set).parameters  # ident's own starts (issue 13) or the runner's
    single, three = {}, {}
    for name in SETS:
        for starts, out in ((("lra",), single), (("lra", "arx", "eiv"), three)):
            if with_init:  # the paper's start, and ident's defaults
                result = run_set(name, directory=DAISY, download_missing=False,
                                 init="lra" if starts == ("lra",) else "auto")
            else:
                result = run_set(name, directory=DAISY, download_missing=False, starts=starts)
            out[name] = {mode: {"start": r.start, "M": h(r.misfit), "iter": r.iterations, "fit": h(r.fit),
                                "p_ell_condition": h(r.p_ell_condition),
                                "candidates": [[c.start, *candidate_numbers(c)] for c in r.candidates]}
                         for mode, r in result.modes.items()}
        print(name, {m: (single[name][m]["M"], single[name][m]["iter"]) for m in single[name]}, flush=True)
    return single, three


def candidate_numbers(c):
    """Misfit (or the error) and iterations of a runner's candidate, before and after issue 13."""
    info = getattr(c, "info", c)
    if getattr(c, "error", ""):
        return [c.error, None]
    return [h(info.M if hasattr(info, "M") else info.misfit), info.iter if hasattr(info, "iter") else info.iterations]


def solver_alone():
    import numpy as np
    try:
        from ident.solver import SLRAWarning, slra
    except ImportError:  # before the solver was a package
        from ident.slra import SLRAWarning, slra
    from ident import daisy as daisy_sets
    from ident.structure import Structure
    out = {}
    for name in SETS:
        meta = daisy_sets.dataset(name)
        u, y = daisy_sets.load(name, DAISY, download_missing=False)
        w = np.hstack([u, y])
        w = w - w.mean(axis=0)
        w = w[: math.ceil(0.7 * len(w))]
        structure = Structure.time_major(w.shape[1], meta.ell, [len(w) - meta.ell])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SLRAWarning)
            r = slra(structure.params_from_series([w]), structure, (meta.ell + 1) * w.shape[1] - meta.p,
                     maxiter=100)
        out[name] = {"M": h(r.misfit), "iter": r.iterations, "nfev": r.nfev, "converged": r.converged,
                     "message": r.message, "time": r.time}
        print(name, out[name]["M"], r.iterations, f"{r.time:.3f}s", flush=True)
    return out


def collect(value, depth=0):
    """Misfits and iterations found in an example's variable (IdentInfo, SLRAResult, lists, dicts)."""
    if hasattr(value, "M") and hasattr(value, "iter"):
        return {"M": h(value.M), "iter": int(value.iter)}
    if hasattr(value, "misfit") and hasattr(value, "iterations") and hasattr(value, "nfev"):
        return {"M": h(value.misfit), "iter": int(value.iterations)}
    if depth < 2 and isinstance(value, (list, tuple)) and value and not isinstance(value, str):
        items = [collect(v, depth + 1) for v in value]
        return items if any(i is not None for i in items) else None
    if depth < 2 and isinstance(value, dict) and value:
        items = {str(k): collect(v, depth + 1) for k, v in value.items()}
        items = {k: v for k, v in items.items() if v is not None}
        return items or None
    return None


def examples(root):
    import contextlib
    import io

    import tangle
    web = tangle.read_web(root)
    out = {}
    for doc in web.documents:
        namespace = {"__name__": f"example:{doc.path}"}
        found = {}
        for block in doc.items:
            if not (isinstance(block, tangle.Block) and block.kind == "example"):
                continue
            source = "\n" * (block.body_location.line - 1) + "\n".join(block.lines) + "\n"
            with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
                warnings.simplefilter("ignore")
                exec(compile(source, str(root / block.location.file), "exec"), namespace)
            for key, value in list(namespace.items()):
                if key.startswith("_"):
                    continue
                got = collect(value)
                if got is not None:
                    found[key] = got
        if found:
            out[doc.path] = found
        print(doc.path, len(found), flush=True)
    return out


def compare(before, after):
    """Print every recorded number that differs (floats with their relative difference)."""
    def walk(x, y, path):
        if isinstance(x, dict):
            for key in x:
                if key != "time":
                    walk(x[key], y.get(key), path + [key]) if key in y else print("missing", "/".join(path + [key]))
        elif isinstance(x, list):
            if len(x) != len(y):
                print("length", "/".join(map(str, path)), len(x), len(y))
            for k, (u, v) in enumerate(zip(x, y)):
                walk(u, v, path + [k])
        elif x != y:
            try:
                u, v = float.fromhex(x), float.fromhex(y)
                print("differs", "/".join(map(str, path)), u, v, f"relative {(v - u) / u if u else v:.1e}")
            except (TypeError, ValueError):
                print("differs", "/".join(map(str, path)), x, y)
    walk(before, after, [])


if __name__ == "__main__":
    if sys.argv[1] == "--compare":
        compare(*(json.loads(Path(name).read_text()) for name in sys.argv[2:4]))
        sys.exit(0)
    root, out = Path(sys.argv[1]).resolve(), Path(sys.argv[2]).resolve()
    setup(root)
    parts = sys.argv[3:] or ["examples", "solver", "runner"]
    result = json.loads(out.read_text()) if out.exists() else {}
    if "examples" in parts:
        result["examples"] = examples(root)
        out.write_text(json.dumps(result, indent=1))
    if "solver" in parts:
        result["solver_alone_maxiter100"] = solver_alone()
        out.write_text(json.dumps(result, indent=1))
    if "runner" in parts:
        result["runner_single_start"], result["runner_three_starts"] = runner()
        out.write_text(json.dumps(result, indent=1))
