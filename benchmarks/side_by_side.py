"""Two versions of the solver side by side, in one run: alternating processes, best of N. Not a test.

Each case runs in a fresh process per version (PYTHONPATH = that checkout's src/), the versions
alternating and their order swapped every round; the best of the rounds is kept per version and the
ratio new / old printed. The machine is shared, so only ratios measured like this compare. The
machine's peak (a 2000 x 2000 matrix product on one BLAS thread, best of 3) is measured in every
round, and the flop rates of the cases that count their flops are given against its best.

Cases:
    scale:T         one series of T samples (benchmarks/bench_scaling.py's 2 x 2 system, lag 2): seconds
                    per iteration (solver time / iterations), per Gauss-Newton matrix and per cost
                    evaluation at the solution (best of 3 in the process), tracemalloc peak of a run with
                    maxiter 2 and the process's resident peak (scale:T:mem; tracemalloc counts allocated
                    pages never touched, such as the band past a factored prefix)
    split:NxK       the same system, N series of K samples each (N K samples in all), per iteration
    short:NxK       N series of K samples of a SISO lag-1 system through ident (issue 16's 3000 x 3), maxiter 20
    daisy           DAISY Table 1, errors-in-variables, the paper's single start (ident.daisy_runner.run_set,
                    maxiter 500): seconds of ident summed over the 17 sets (python-control imported
                    before), the solver's own seconds (solver_seconds), iterations
    daisy:SET       one set of it
    daisy-plain     the same without the runner's refinement to 1e-12 (ident.daisy_runner.REFINE = None where the
                    version has it): both versions then stop at the runner's tol 1e-5, the same work
    peak            the matrix product alone

Usage: python benchmarks/side_by_side.py OLD_ROOT [NEW_ROOT] [--rounds=3] [--json=FILE] CASE ...
--json=FILE also writes the best of the rounds per measure, the ratios, every round and the load
averages to FILE (merged into it case by case, so that cases measured in separate runs share a file).
(NEW_ROOT defaults to this checkout; e.g. OLD_ROOT = a `git worktree add /work/perf-base 4e3dfb5`.)
"""
import json
import math
import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
DAISY = HERE.parents[1] / "shared" / "daisy"


# ---------------------------------------------------------------- the worker (one case, one version)
def _slra():
    try:
        from ident.solver import SLRAWarning, slra
    except ImportError:  # before the solver was a package
        from ident.slra import SLRAWarning, slra
    return slra, SLRAWarning


def _problem_class():
    try:
        from ident.solver.cost import Problem
        return Problem
    except ImportError:
        from ident.slra import _Problem
        return _Problem


def peak_rate(n=2000, repeats=3):
    """GFLOP/s of an n x n matrix product on one BLAS thread (best of repeats)."""
    import numpy as np
    import threadpoolctl
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((n, n)), rng.standard_normal((n, n))
    with threadpoolctl.threadpool_limits(1, "blas"):
        best = math.inf
        for _ in range(repeats):
            started = time.perf_counter()
            a @ b
            best = min(best, time.perf_counter() - started)
    return 2 * n ** 3 / best / 1e9


def system_data(n_samples, seed=0, system_seed=0):
    """benchmarks/bench_scaling.py's data: a random stable 2 x 2 system of order 4, noise 0.1."""
    import numpy as np
    rng = np.random.default_rng(system_seed)
    n, m, p = 4, 2, 2
    A = rng.standard_normal((n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    B, C, D = (rng.standard_normal(s) for s in ((n, m), (p, n), (p, m)))
    if seed != system_seed:
        rng = np.random.default_rng(seed)
    u = rng.standard_normal((n_samples, m))
    x = rng.standard_normal(n)
    states = np.empty((n_samples, n))
    for t in range(n_samples):
        states[t] = x
        x = A @ x + B @ u[t]
    w = np.hstack([u, states @ C.T + u @ D.T])
    return w + 0.1 * rng.standard_normal(w.shape)


def split_data(n_series, n_samples):
    """N series of the same system (different inputs, initial states and noise) in one array."""
    import numpy as np
    whole = system_data(n_series * n_samples)
    return [whole[k * n_samples: (k + 1) * n_samples] for k in range(n_series)]


def run_slra(series, maxiter=100):
    import numpy as np
    from ident.structure import Structure
    slra, SLRAWarning = _slra()
    structure = Structure.time_major(4, 2, [len(w) - 2 for w in series])
    p = structure.params_from_series(series)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SLRAWarning)
        started = time.process_time()
        result = slra(p, structure, 10, maxiter=maxiter)
        result.cpu = time.process_time() - started
    return structure, p, result


def case_scale(n_samples, memory=False):
    import numpy as np
    structure, p, result = run_slra([system_data(n_samples)])
    out = {"seconds": result.time, "iterations": result.iterations, "nfev": result.nfev,
           "per_iteration": result.time / max(result.iterations, 1),
           "cpu_per_iteration": result.cpu / max(result.iterations, 1), "misfit": result.misfit}
    Problem = _problem_class()
    problem = Problem(p, structure)
    free = _chart_class().from_kernel(result.R).free_columns
    threads = _one_thread()
    with threads():
        best_cost = best_jacobian = math.inf
        for _ in range(3):
            started = time.perf_counter()
            state = problem.evaluate(result.R)
            best_cost = min(best_cost, time.perf_counter() - started)
            started = time.perf_counter()
            (getattr(problem, "normal_equations", None) or problem.normal_equations_projection)(state, free)
            best_jacobian = min(best_jacobian, time.perf_counter() - started)
    out.update(cost_evaluation=best_cost, gauss_newton=best_jacobian)
    if memory:
        import tracemalloc
        slra, SLRAWarning = _slra()
        tracemalloc.start()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SLRAWarning)
            slra(p, structure, 10, maxiter=2)
        out["tracemalloc_peak_gb"] = tracemalloc.get_traced_memory()[1] / 1e9
        tracemalloc.stop()
        import resource  # the process's resident peak (data generation and the runs above included):
        out["resident_peak_gb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6  # untouched pages not counted

    return out


def _chart_class():
    try:
        from ident.solver.optimiser import Chart
        return Chart
    except ImportError:
        from ident.slra import _Chart
        return _Chart


def _one_thread():
    try:
        from ident.solver.threads import one_blas_thread
        return one_blas_thread
    except ImportError:
        from ident.slra import _one_blas_thread
        return _one_blas_thread


def case_split(n_series, n_samples):
    structure, p, result = run_slra(split_data(n_series, n_samples))
    return {"seconds": result.time, "iterations": result.iterations, "nfev": result.nfev,
            "per_iteration": result.time / max(result.iterations, 1),
            "cpu_per_iteration": result.cpu / max(result.iterations, 1), "misfit": result.misfit}


def case_short(n_series, n_samples):
    """Issue 16's case: many short series of a SISO system, ident(w, 1, 1, maxiter=20)."""
    import numpy as np
    from ident import ident
    rng = np.random.default_rng(0)
    series = []
    for _ in range(n_series):
        u = rng.standard_normal(n_samples)
        y = np.zeros(n_samples)
        y[0] = rng.standard_normal()
        for t in range(1, n_samples):
            y[t] = 0.7 * y[t - 1] + u[t - 1]
        series.append(np.column_stack([u, y]) + 0.1 * rng.standard_normal((n_samples, 2)))
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, info, _, _ = ident(series, 1, 1, maxiter=20)
    seconds = time.perf_counter() - started
    return {"seconds": seconds, "iterations": info.iter, "per_iteration": seconds / max(info.iter, 1),
            "misfit": info.M}


def case_daisy(names=None, refine=True):
    try:
        from ident.daisy_runner import run_set
        from ident import daisy_runner
        if not refine and hasattr(daisy_runner, "REFINE"):
            daisy_runner.REFINE = None  # benchmark_options reads it at each call
    except ImportError:
        from ident.daisy import run_set
    from ident import daisy as daisy_sets
    names = names or [info.name for info in daisy_sets.table1()]
    import control  # noqa: F401  imported before the clock starts (later versions import it on first use)
    try:  # the module that calls the solver for ident: ident.multistart since issue 28, ident.identification before
        from ident import multistart
    except ImportError:
        from ident import identification as multistart
    solver_seconds = []  # the solver's own seconds (SLRAResult.time) of every call of ident's slra
    solve = multistart.slra

    def timed_slra(*args, **kwargs):
        result = solve(*args, **kwargs)
        solver_seconds.append(result.time)
        return result

    multistart.slra = timed_slra
    out = {"seconds": 0.0, "iterations": 0, "sets": {}}
    for name in names:
        started = time.perf_counter()
        try:  # the paper's single start: starts=("lra",) before ident's init option, init="lra" since
            result = run_set(name, directory=DAISY, download_missing=False, modes=("eiv",), init="lra")
        except TypeError:
            result = run_set(name, directory=DAISY, download_missing=False, modes=("eiv",), starts=("lra",))
        wall = time.perf_counter() - started
        mode = result.modes["eiv"]
        candidate = mode.candidates[0]
        out["seconds"] += candidate.seconds
        out["iterations"] += mode.iterations
        out["sets"][name] = {"seconds": candidate.seconds, "wall": wall, "iterations": mode.iterations,
                             "misfit": mode.misfit}
    out["per_iteration"] = out["seconds"] / max(out["iterations"], 1)
    out["solver_seconds"] = sum(solver_seconds)  # without what ident does around the solver
    return out


def worker(case):
    kind, _, argument = case.partition(":")
    if kind == "scale":
        size, _, memory = argument.partition(":")
        result = case_scale(int(float(size)), memory == "mem")
    elif kind == "split":
        n_series, n_samples = (int(float(x)) for x in argument.split("x"))
        result = case_split(n_series, n_samples)
    elif kind == "short":
        n_series, n_samples = (int(float(x)) for x in argument.split("x"))
        result = case_short(n_series, n_samples)
    elif kind == "daisy":
        result = case_daisy([argument] if argument else None)
    elif kind == "daisy-plain":
        result = case_daisy([argument] if argument else None, refine=False)
    elif kind == "peak":
        result = {}
    else:
        raise SystemExit(f"unknown case {case}")
    result["peak_gflops"] = peak_rate()
    print(json.dumps(result))


# ---------------------------------------------------------------- the driver
def run_version(root, case):
    environment = dict(os.environ, PYTHONPATH=str(Path(root) / "src"))
    completed = subprocess.run([sys.executable, __file__, "--worker", case], env=environment,
                               capture_output=True, text=True)
    if completed.returncode != 0:
        raise SystemExit(f"{root} {case} failed:\n{completed.stderr}")
    return json.loads(completed.stdout.strip().splitlines()[-1])


def main(argv):
    if argv and argv[0] == "--worker":
        worker(argv[1])
        return
    options = dict(a.lstrip("-").partition("=")[::2] for a in argv if a.startswith("--"))
    positional = [a for a in argv if not a.startswith("--")]
    roots = [p for p in positional if Path(p).is_dir()]
    cases = [p for p in positional if p not in roots]
    old = Path(roots[0]).resolve()
    new = Path(roots[1]).resolve() if len(roots) > 1 else HERE.parent
    rounds = int(options.get("rounds", 3))
    print(f"old {old}\nnew {new}\nload average at start {os.getloadavg()}", flush=True)
    record = {}
    for case in cases:
        load_before = os.getloadavg()[0]
        runs = {"old": [], "new": []}
        for k in range(rounds):
            order = [("old", old), ("new", new)] if k % 2 == 0 else [("new", new), ("old", old)]
            for label, root in order:
                result = run_version(root, case)
                runs[label].append(result)
                print(f"  {case} round {k + 1} {label}: " + ", ".join(
                    f"{name} {value:.4g}" if isinstance(value, float) else f"{name} {value}"
                    for name, value in result.items() if not isinstance(value, dict)), flush=True)
        peak = max(r["peak_gflops"] for label in runs for r in runs[label])
        print(f"{case}: best of {rounds} per measure; machine peak {peak:.1f} GFLOP/s (one thread, best); "
              f"load average now {os.getloadavg()[0]:.1f}")
        for name, value in runs["old"][0].items():
            if name == "peak_gflops" or not isinstance(value, (int, float)):
                continue
            a = min(r[name] for r in runs["old"])
            b = min(r.get(name, float("nan")) for r in runs["new"])
            print(f"    {name:22s} old {a:12.5g}  new {b:12.5g}  new/old {b / a if a else float('nan'):7.3f}")
        print(flush=True)
        record[case] = _summary(runs, rounds, peak, load_before)
    if options.get("json"):
        _write_json(Path(options["json"]), record, old, new)


def _summary(runs, rounds, peak, load_before):
    """The best of the rounds per numeric measure and version, the ratios new / old, every round."""
    best = {label: {name: min(r[name] for r in runs[label] if name in r)
                    for name, value in runs[label][0].items() if isinstance(value, (int, float))}
            for label in runs}
    ratio = {name: best["new"][name] / best["old"][name] for name in best["old"]
             if name in best["new"] and best["old"][name]}
    return {"rounds": rounds, "best": best, "new_over_old": ratio, "machine_peak_gflops": peak,
            "load_average_before": load_before, "load_average_after": os.getloadavg()[0], "runs": runs}


def _write_json(path, record, old, new):
    """Merge this run's cases into the JSON file (cases of earlier runs kept)."""
    import subprocess as sp
    data = json.loads(path.read_text()) if path.exists() else {}
    commits = {label: sp.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True).stdout.strip() for label, root in (("old", old), ("new", new))}
    for case, summary in record.items():
        data[case] = dict(summary, commits=commits, date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()))
    path.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
