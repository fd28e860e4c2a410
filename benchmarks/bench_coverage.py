"""Coverage of ident's error bars (issue 34, 30-uncertainty-and-stability.md), and their cost on DAISY. Not a test.

Monte Carlo: for each of four settings (a second-order SISO plant and a 2x2 plant of order 2, each
errors-in-variables and output error) RUNS records are simulated with a fresh white input and fresh
white Gaussian errors at a signal-to-noise ratio of about 20 dB (errors of one standard deviation
SIGMA_RATIO times the root-mean-square of the true variables, on every variable in EIV, on the
outputs in OE). Each is identified with ident(..., uncertainty=True) (init "auto", refine 1e-10) and
the nominal 95 % interval (value +- 1.96 std, the delta method) of every pole's real part, every
complex pole's imaginary part and every entry of the steady-state gain is checked against the true
value (poles paired with the true ones by least total distance). The coverage is the fraction of
runs whose interval holds the true value; a run whose identification fails counts as not covered.

DAISY: for each of the 17 sets of Table 1 and both modes, the runner's identification (the
protocol's centring by the record's means, maxiter 500, tol 1e-5, refine 1e-12, init "auto") is
timed, then model_uncertainty on the same data and the propagation to poles and gain; the cost is
their time over the identification's.

Writes benchmarks/results/coverage.json. Usage: python benchmarks/bench_coverage.py [--runs N] [--no-daisy]
"""
from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import control
import numpy as np

from ident import daisy, ident, model_uncertainty

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the examples' helpers (03-examples.md) are the repository's, not the package's
from literate_tools.tangled.examples import match_eigenvalues  # noqa: E402
DAISY = ROOT.parent / "shared" / "daisy"
RESULTS = ROOT / "benchmarks" / "results" / "coverage.json"
SIGMA_RATIO = 0.1  # error std / rms of the true variables: 20 dB
Z95 = 1.959963984540054

PLANTS = {
    "siso": (control.ss(control.tf([0.2, 0.12], [1, -1.2, 0.5], 1)), 2, 200),
    "2x2": (control.ss([[0.6, 0.2], [0.1, 0.5]], [[1.0, 0.0], [0.3, 1.0]], np.eye(2), np.zeros((2, 2)), 1), 1, 300),
}


def simulated(plant, n_samples: int, mode: str, rng) -> tuple[np.ndarray, float]:
    u = rng.standard_normal((n_samples, plant.ninputs))
    y = np.atleast_2d(control.forced_response(plant, U=u.T).outputs).reshape(plant.noutputs, -1).T
    w_true = np.column_stack([u, y])
    sigma = SIGMA_RATIO * np.sqrt(np.mean(w_true ** 2))
    errors = sigma * rng.standard_normal(w_true.shape)
    if mode == "oe":
        errors[:, : plant.ninputs] = 0
    snr = 10 * np.log10(np.mean(w_true[:, plant.ninputs:] ** 2) / sigma ** 2)
    return w_true + errors, snr


def one_run(plant, ell: int, n_samples: int, mode: str, rng) -> dict:
    w, snr = simulated(plant, n_samples, mode, rng)
    m = plant.ninputs
    true_poles, true_gain = plant.poles(), np.asarray(control.dcgain(plant)).reshape(plant.noutputs, m)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sysh, info, _, _ = ident(w, m, ell, exct=list(range(m)) if mode == "oe" else None, refine=1e-10,
                                     uncertainty=True)
    except (ValueError, np.linalg.LinAlgError) as error:
        return {"error": str(error), "snr": snr}
    bars = info.uncertainty
    poles, pole_std = bars.value("poles"), bars.std("poles")
    match = match_eigenvalues(poles, true_poles)
    partner = true_poles[match.partner]
    order = np.argsort(partner.real * 10 + partner.imag)  # the true poles' order, the same in every run
    gain, gain_std = bars.value("gain"), bars.std("gain")
    return {"snr": snr, "pole_error": [[float((poles - partner)[k].real), float((poles - partner)[k].imag)] for k in order],
            "pole_std": [[float(pole_std[k].real), float(pole_std[k].imag)] for k in order],
            "complex": [bool(abs(partner[k].imag) > 0) for k in order],
            "gain_error": (gain - true_gain).ravel().tolist(), "gain_std": gain_std.ravel().tolist()}


def coverage(runs: list[dict]) -> dict:
    """The fraction of runs covering the true value, per quantity, and the ratio of the observed spread
    of the estimates to the mean predicted standard deviation."""
    done = [run for run in runs if "error" not in run]
    out = {}
    first = done[0]
    quantities = [(f"pole {k} real", "pole_error", "pole_std", (k, 0)) for k in range(len(first["pole_std"]))]
    quantities += [(f"pole {k} imag", "pole_error", "pole_std", (k, 1)) for k in range(len(first["pole_std"]))
                   if first["complex"][k]]
    quantities += [(f"gain {k}", "gain_error", "gain_std", (k,)) for k in range(len(first["gain_std"]))]
    for name, error_key, std_key, index in quantities:
        errors = np.array([np.array(run[error_key])[index] for run in done])
        stds = np.array([np.array(run[std_key])[index] for run in done])
        covered = int(np.sum(np.abs(errors) <= Z95 * stds))
        out[name] = {"coverage": covered / len(runs), "covered": covered, "runs": len(runs),
                     "spread_over_predicted": float(np.std(errors, ddof=1) / np.mean(stds))}
    return out


def monte_carlo(n_runs: int) -> dict:
    results = {}
    for plant_name, (plant, ell, n_samples) in PLANTS.items():
        for mode in ("eiv", "oe"):
            rng = np.random.default_rng(34)
            started = time.perf_counter()
            runs = [one_run(plant, ell, n_samples, mode, rng) for _ in range(n_runs)]
            setting = f"{plant_name} {mode}"
            results[setting] = {"runs": n_runs, "samples": n_samples, "ell": ell,
                                "failed": sum("error" in run for run in runs),
                                "snr_db": float(np.mean([run["snr"] for run in runs])),
                                "seconds": time.perf_counter() - started, "quantities": coverage(runs)}
            worst = min(q["coverage"] for q in results[setting]["quantities"].values())
            best = max(q["coverage"] for q in results[setting]["quantities"].values())
            print(f"{setting}: coverage {100 * worst:.1f} .. {100 * best:.1f} % over "
                  f"{len(results[setting]['quantities'])} quantities, {n_runs} runs, "
                  f"{results[setting]['seconds']:.0f} s", flush=True)
    return results


def daisy_cost() -> dict:
    settings = {"maxiter": 500, "tol": 1e-5, "refine": 1e-12}
    results = {}
    for info in daisy.table1():
        u, y = daisy.load(info.name, DAISY, download_missing=False)
        w = np.hstack([u, y])
        w = w - w.mean(axis=0)
        for mode in ("oe", "eiv"):
            exact = list(range(info.m)) if mode == "oe" else None
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                started = time.perf_counter()
                sysh, ident_info, _, _ = ident(w, info.m, info.ell, exct=exact, **settings)
                identification = time.perf_counter() - started
                started = time.perf_counter()
                bars = model_uncertainty(w, sysh, ident_info, exct=exact)
                covariance = time.perf_counter() - started
                bars.std("poles"), bars.std("gain")
                total = time.perf_counter() - started
            results[f"{info.name} {mode}"] = {
                "identification_s": identification, "covariance_s": covariance, "with_propagation_s": total,
                "ratio": total / identification, "finite": bool(np.all(np.isfinite(bars.std("gain")))),
                "reason": bars.reason}
            print(f"{info.name:18s} {mode}: identification {identification:.3f} s, covariance {covariance:.3f} s, "
                  f"with poles and gain {total:.3f} s ({100 * total / identification:.1f} %)", flush=True)
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=500)
    parser.add_argument("--no-daisy", action="store_true")
    arguments = parser.parse_args()
    results = json.loads(RESULTS.read_text()) if RESULTS.exists() else {}
    results["monte_carlo"] = monte_carlo(arguments.runs)
    results["settings"] = {"sigma_ratio": SIGMA_RATIO, "level": 0.95, "bar": [0.92, 0.98]}
    RESULTS.write_text(json.dumps(results, indent=1, sort_keys=True) + "\n")
    if not arguments.no_daisy:
        results["daisy"] = daisy_cost()
        RESULTS.write_text(json.dumps(results, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    main()
