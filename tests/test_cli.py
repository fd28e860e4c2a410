"""ident.cli: identify, daisy and lag through main(argv); usage errors are one line with exit status 2."""
from __future__ import annotations

import contextlib
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

from ident import cli
from ident.solver import Status
from ident.representations import random_system, simulate

SHARED = Path(__file__).resolve().parents[2] / "shared" / "daisy"


@pytest.fixture
def data_csv(tmp_path) -> Path:
    """A two-input, one-output system of lag 2 with a little output noise, with a header row."""
    rng = np.random.default_rng(5)
    system = random_system(2, 1, 2, rng)
    u = rng.standard_normal((300, 2))
    y = simulate(system, u, rng.standard_normal(2)) + 0.01 * rng.standard_normal((300, 1))
    path = tmp_path / "plant.csv"
    np.savetxt(path, np.hstack([u, y]) + 10.0, delimiter=",", header="u1,u2,y", comments="")
    return path


def run(argv, capsys) -> tuple[int, str, str]:
    status = cli.main([str(a) for a in argv])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def test_identify_prints_and_writes(data_csv, tmp_path, capsys):
    model, plot = tmp_path / "m.json", tmp_path / "fit.png"
    status, out, err = run(["identify", data_csv, "--inputs", "u1,u2", "--outputs", "y", "--lag", 2,
                            "--exact", "inputs", "--model", model, "--plot", plot], capsys)
    assert status == 0, err
    assert "identified from 210 samples" in out and "exact: u1, u2" in out
    assert "misfit M =" in out and "validation fit on the last 90 samples" in out and "A =" in out
    saved = json.loads(model.read_text())
    assert {"A", "B", "C", "D", "means", "misfit", "fit"} <= saved.keys()
    assert np.array(saved["B"]).shape == (2, 2) and saved["fit"] > 95
    assert saved["means"]["outputs"][0] == pytest.approx(10, abs=1)  # centred, means kept
    assert plot.stat().st_size > 1000


def test_identify_from_npz_with_u_and_y_and_default_outputs(tmp_path, capsys, monkeypatch):
    rng = np.random.default_rng(6)
    system = random_system(1, 1, 1, rng)
    u = rng.standard_normal(200)
    np.savez(tmp_path / "run.npz", u=u, y=simulate(system, u))
    monkeypatch.chdir(tmp_path)
    status, out, err = run(["identify", "run.npz", "--lag", 1, "--zero-initial", "--holdout", 0], capsys)
    assert status == 0, err
    assert "on the identification data (no hold-out)" in out
    assert (tmp_path / "run_model.json").is_file() and (tmp_path / "run_fit.png").is_file()


@pytest.mark.parametrize("argv, expected", [
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3"], "required: --lag"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "two"],
     "argument --lag: must be a non-negative integer, got 'two'"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "-1"],
     "argument --lag: must be a non-negative integer, got -1"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "10", "--lag", "1"], "--outputs: columns are counted from 1 to 3"),
    (["identify", "{csv}", "--inputs", "speed", "--outputs", "3", "--lag", "1"], "'speed' is neither"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "1", "--lag", "1"], "share columns"),
    (["identify", "{csv}", "--outputs", "3", "--lag", "1"], "--inputs and --outputs are required"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--holdout", "1.5"], "--holdout"),
    (["identify", "missing.csv", "--inputs", "1", "--outputs", "3", "--lag", "1"], "does not exist"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--bogus"], "unrecognized arguments"),
    (["frobnicate"], "invalid choice"),
    (["daisy", "nowhere"], "unknown data set(s) nowhere"),
    (["daisy", "--modes", "ml"], "invalid choice"),
    (["lag", "nowhere"], "neither a data file nor a DAISY data set"),
    (["lag", "{csv}", "--lags", "a-b", "--inputs", "1", "--outputs", "3"], "--lags must look like"),
    # every option is validated and named (issue 16)
    (["identify", "{csv}", "--inputs", "1,1", "--outputs", "3", "--lag", "1"],
     "--inputs: column(s) 'u1' given more than once in '1,1'"),
    (["identify", "{csv}", "--inputs", "u1,1", "--outputs", "3", "--lag", "1"], "--inputs: column(s) 'u1' given more"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "none", "--lag", "1"],
     "--outputs: 'none' is not possible here (a model needs at least one output)"),
    (["identify", "{csv}", "--inputs", "3-1", "--outputs", "3", "--lag", "1"], "--inputs: the range '3-1' selects no column"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--maxiter", "-1"],
     "argument --maxiter: must be a non-negative integer, got -1"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--tol", "0"],
     "argument --tol: must be a finite positive number, got 0"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--tol", "nan"],
     "argument --tol: must be a finite positive number, got nan"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--holdout", "-0.5"],
     "argument --holdout: must be a fraction in [0, 1), got -0.5"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--plot", "{tmp}/missing/fit.png"],
     "--plot: the folder {tmp}/missing does not exist"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--plot", "{tmp}/fit.xyz"],
     "--plot: {tmp}/fit.xyz must end in one of"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--model", "{tmp}/missing/m.json"],
     "--model: the folder {tmp}/missing does not exist"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--model", "{tmp}"],
     "--model: {tmp} is a folder; give a file name"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--exact", "1,3"],
     "--exact: at most m = 1 columns can be exact"),
    (["identify", "{tmp}", "--inputs", "1", "--outputs", "3", "--lag", "1"], "is a folder, not a file"),
    (["daisy", "erie", "--maxiter", "-1"], "argument --maxiter: must be a non-negative integer, got -1"),
    (["daisy", "erie", "--tol=-1e-5"], "argument --tol: must be a finite positive number, got -1e-5"),
    (["daisy", "erie", "--out", "{csv}"], "--out: {csv} is a file, not a folder"),
    (["identify", "{csv}", "--inputs", "1", "--outputs", "3", "--lag", "1", "--init", "sys0"],
     "argument --init: invalid choice: 'sys0'"),  # the caller's start is a model, not a name of the table
    (["lag", "{csv}", "--inputs", "1", "--outputs", "3", "--holdout", "1.5"],
     "argument --holdout: must be a fraction in [0, 1), got 1.5"),
    (["lag", "{csv}", "--inputs", "1", "--outputs", "3", "--holdout", "-0.5"], "argument --holdout: must be a fraction"),
    (["lag", "{csv}", "--inputs", "1", "--outputs", "3", "--maxiter", "-3"], "argument --maxiter: must be a non-negative"),
    (["lag", "{csv}", "--inputs", "1", "--outputs", "3", "--lags", "5-1"], "--lags must give non-negative lags"),
    (["lag", "{tmp}", "--inputs", "1", "--outputs", "3"], "is a folder, not a data file"),
    (["lag", "{csv}", "--inputs", "1", "--outputs", "3", "--plot", "{tmp}/missing/lag.png"],
     "--plot: the folder {tmp}/missing does not exist"),
])
def test_bad_arguments_exit_2_with_one_line(argv, expected, data_csv, capsys):
    def filled(text: str) -> str:
        return text.replace("{csv}", str(data_csv)).replace("{tmp}", str(data_csv.parent))
    before = sorted(data_csv.parent.iterdir())
    status, out, err = run([filled(a) for a in argv], capsys)
    expected = filled(expected)
    assert sorted(data_csv.parent.iterdir()) == before  # a refused run writes nothing
    assert status == 2
    assert len(err.strip().splitlines()) == 1 and expected in err and "Traceback" not in err
    assert err.startswith("python -m ident")


def test_a_file_that_is_not_a_table(tmp_path, capsys):
    bad = tmp_path / "notes.csv"
    bad.write_text("a,b\n1,2\nthree,4\n")
    status, _, err = run(["identify", bad, "--inputs", "a", "--outputs", "b", "--lag", "1"], capsys)
    assert status == 2 and "not a numeric table" in err and len(err.strip().splitlines()) == 1


def test_an_impossible_identification_exits_1_with_one_line(data_csv, capsys):
    status, _, err = run(["identify", data_csv, "--inputs", "1", "--outputs", "3", "--lag", "500"], capsys)
    assert status == 1 and "lag ell = 500" in err and len(err.strip().splitlines()) == 1


def test_help_exits_0(capsys):
    status, out, _ = run(["identify", "--help"], capsys)
    assert status == 0 and "--exact" in out and "--zero-initial" in out


def test_the_module_runs_as_a_program_without_traceback(tmp_path):
    environment = {**os.environ, "PYTHONWARNINGS": "ignore"}
    done = subprocess.run([sys.executable, "-m", "ident.cli", "identify", str(tmp_path / "none.csv"), "--lag", "1"],
                          capture_output=True, text=True, timeout=120, env=environment)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "Traceback" not in done.stderr



@pytest.mark.parametrize("argv0, prog", [("/usr/local/bin/ident", "ident"), ("C:\\env\\Scripts\\ident.exe", "ident"),
                                         ("/x/ident/__main__.py", "python -m ident")])
def test_help_names_the_program_as_started(monkeypatch, capsys, argv0, prog):
    from ident.__main__ import main as program
    monkeypatch.setattr(sys, "argv", [argv0.replace("\\", "/")])
    assert program(["identify", "--help"]) == 0
    assert capsys.readouterr().out.startswith(f"usage: {prog} identify")

def test_lag_on_a_csv_file(data_csv, tmp_path, capsys):
    plot = tmp_path / "lag.png"
    status, out, err = run(["lag", data_csv, "--inputs", "1-2", "--outputs", "y", "--lags", "1-3", "--modes", "oe",
                            "--plot", plot], capsys)
    assert status == 0, err
    lines = out.splitlines()
    assert lines[1] == "lag | OE misfit | OE fit %" and len(lines) >= 5 and plot.stat().st_size > 1000
    chosen = [line for line in lines if line.startswith("chosen lag (OE, hold-out rule on the identification data): ")]
    assert len(chosen) == 1 and "by lag: 1: " in chosen[0], out
    status, out, err = run(["lag", data_csv, "--inputs", "1-2", "--outputs", "y", "--lags", "0", "--modes", "oe",
                            "--plot", plot], capsys)
    assert status == 0 and "no lag chosen (OE): the hold-out rule chooses among positive lags" in out, err


def test_daisy_and_lag_on_a_data_set(tmp_path, capsys):
    if not (SHARED / "erie.dat").is_file():
        pytest.skip(f"the DAISY files are not in {SHARED}")
    status, out, err = run(["daisy", "erie", "--data-dir", SHARED, "--no-download", "--out", tmp_path / "out",
                            "--quiet", "--init", "lra", "--maxiter", "30"], capsys)
    assert status == 0, err
    assert "mean validation fit over 1 sets" in out and (tmp_path / "out" / "figure1.png").is_file()
    results = json.loads((tmp_path / "out" / "results.json").read_text())
    assert results["settings"]["init"] == ["lra"]
    assert [c["start"] for c in results["sets"][0]["modes"]["eiv"]["candidates"]] == ["lra"]
    status, _, err = run(["daisy", "erie", "--out", tmp_path / "out2", "--init", "auto", "lra"], capsys)
    assert status == 2 and "--init: 'auto' stands alone" in err
    status, out, err = run(["lag", "erie", "--data-dir", SHARED, "--lags", "1,2", "--modes", "eiv", "--maxiter", "20",
                            "--plot", tmp_path / "erie.png"], capsys)
    assert status == 0, err
    assert out.startswith("erie: misfit on 40 samples, fit on the next 17")


def test_a_missing_data_set_without_download_exits_1(tmp_path, capsys):
    status, _, err = run(["daisy", "erie", "--data-dir", tmp_path, "--no-download", "--quiet"], capsys)
    assert status == 1 and "erie.dat is not in" in err and len(err.strip().splitlines()) == 1


def test_build_parser_takes_more_subcommands(capsys):
    parser = cli.build_parser()
    demo = parser.commands.add_parser("demo", help="a demonstration")
    demo.add_argument("--seed", type=int, default=1)
    demo.set_defaults(handler=lambda args: print(f"demo {args.seed}") or 0)
    assert cli.main(["demo", "--seed", "3"], parser=parser) == 0
    assert capsys.readouterr().out == "demo 3\n"


# --- bad data files are refused in the file's own terms, and a failed run writes nothing (issue 16) ---

def npz_data(tmp_path: Path, n_samples: int = 200, **overrides) -> Path:
    rng = np.random.default_rng(8)
    system = random_system(1, 1, 1, rng)
    u = rng.standard_normal(n_samples)
    arrays = {"u": u, "y": simulate(system, u), **overrides}
    np.savez(tmp_path / "run.npz", **arrays)
    return tmp_path / "run.npz"


def refused(argv, capsys, expected: str, folder: Path) -> None:
    before = sorted(folder.iterdir())
    status, out, err = run(argv, capsys)
    assert status == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert expected in err, err
    assert sorted(folder.iterdir()) == before


def test_truncated_npz(tmp_path, capsys):
    path = npz_data(tmp_path)
    path.write_bytes(path.read_bytes()[:700])
    refused(["identify", path, "--lag", 1], capsys, "as an .npz archive (damaged or truncated?)", tmp_path)


def test_text_under_an_npz_name(tmp_path, capsys):
    (tmp_path / "run.npz").write_text("1,2\n3,4\n")
    refused(["identify", tmp_path / "run.npz", "--lag", 1], capsys, "cannot read", tmp_path)


def test_complex_npz_is_not_cast(tmp_path, capsys):
    path = npz_data(tmp_path, y=np.ones(200) * (1 + 2j))
    refused(["identify", path, "--lag", 1], capsys, "array 'y' of " + str(path) + " holds complex numbers", tmp_path)


def test_object_npz_is_refused(tmp_path, capsys):
    path = tmp_path / "run.npz"
    np.savez(path, u=np.array([1, "a"], dtype=object), y=np.ones(2))
    refused(["identify", path, "--lag", 1], capsys, "cannot read", tmp_path)


def test_u_and_y_of_different_lengths(tmp_path, capsys):
    path = npz_data(tmp_path, y=np.ones(199))
    refused(["identify", path, "--lag", 1], capsys, "u has 200 samples but y has 199", tmp_path)


def test_npy_content_under_an_npz_name(tmp_path, capsys):
    np.save(tmp_path / "table.npy", np.ones((50, 2)))
    (tmp_path / "table.npy").rename(tmp_path / "table.npz")
    refused(["identify", tmp_path / "table.npz", "--inputs", 1, "--outputs", 2, "--lag", 1], capsys,
            "holds a single .npy array, not an .npz archive; name it table.npy", tmp_path)


def test_an_npy_file_is_read(tmp_path, capsys, monkeypatch):
    rng = np.random.default_rng(9)
    system = random_system(1, 1, 1, rng)
    u = rng.standard_normal(200)
    np.save(tmp_path / "table.npy", np.column_stack([u, simulate(system, u)[:, 0]]))
    monkeypatch.chdir(tmp_path)
    status, out, err = run(["identify", "table.npy", "--inputs", 1, "--outputs", 2, "--lag", 1], capsys)
    assert status == 0 and "identified from 140 samples" in out, err


def test_inf_is_reported_in_the_files_terms_before_centring(data_csv, tmp_path, capsys):
    lines = data_csv.read_text().splitlines()
    fields = lines[100].split(",")  # line 101 of the file: the header, then data row 100
    lines[100] = ",".join(fields[:2] + ["inf"])  # NaN is a missing sample, which identify takes
    data_csv.write_text("\n".join(lines) + "\n")
    refused(["identify", data_csv, "--inputs", "u1,u2", "--outputs", "y", "--lag", 1], capsys,
            f"column 'y' holds 1 missing value(s) (NaN or inf), the first in data row 100 (line 101 of {data_csv})",
            tmp_path)


def test_inf_in_an_npz_array(tmp_path, capsys):
    y = np.ones(200)
    y[99] = np.inf
    refused(["identify", npz_data(tmp_path, y=y), "--lag", 1], capsys,
            "column 'y[:, 0]' holds 1 missing value(s) (NaN or inf), the first in sample 99 (0-based) of array 'y'",
            tmp_path)


def test_empty_fields_and_nan_are_missing_samples(data_csv, tmp_path, capsys):
    """identify reads an empty CSV field or NaN as a missing sample (issue 29, 32-missing-data.md) where
    the model is identified; where it is validated by simulation, it refuses them, naming the row."""
    lines = data_csv.read_text().splitlines()
    lines[51] = ",".join(lines[51].split(",")[:2] + [""])  # data row 50: y empty
    lines[81] = "nan," + ",".join(lines[81].split(",")[1:])  # data row 80: u1 NaN
    data_csv.write_text("\n".join(lines) + "\n")
    status, out, err = run(["identify", data_csv, "--inputs", "u1,u2", "--outputs", "y", "--lag", 2,
                            "--model", tmp_path / "model.json", "--plot", tmp_path / "fit.png"], capsys)
    assert status == 0 and "identified from 210 samples" in out and "refined on the missing samples" in out, err
    lines[251] = ",".join(lines[251].split(",")[:2] + [""])  # data row 250: in the held-out part
    data_csv.write_text("\n".join(lines) + "\n")
    refused(["identify", data_csv, "--inputs", "u1,u2", "--outputs", "y", "--lag", 2, "--model", tmp_path / "m2.json",
             "--plot", tmp_path / "fit2.png"],
            capsys, "missing values (empty or NaN) in the samples the model is validated on, from data row 210", tmp_path)


def test_a_constant_input_is_refused_with_its_name(data_csv, tmp_path, capsys):
    table = np.loadtxt(data_csv, delimiter=",", skiprows=1)
    table[:, 1] = 4.0
    np.savetxt(data_csv, table, delimiter=",", header="u1,u2,y", comments="")
    refused(["identify", data_csv, "--inputs", "u1,u2", "--outputs", "y", "--lag", 1], capsys,
            "--inputs: column 'u2' is zero on the 210 samples used for identification (after centring: it is constant)",
            tmp_path)


def test_demo_seed_must_be_non_negative(capsys):
    from ident.__main__ import main as program
    assert program(["demo", "--seed", "-1"]) == 2
    err = capsys.readouterr().err
    assert "argument --seed: must be a non-negative integer, got -1" in err and len(err.strip().splitlines()) == 1


def test_a_failed_identification_keeps_the_previous_results(data_csv, tmp_path, capsys):
    model, plot = tmp_path / "m.json", tmp_path / "fit.png"
    model.write_text("previous model"), plot.write_bytes(b"previous plot")
    status, _, err = run(["identify", data_csv, "--inputs", 1, "--outputs", 3, "--lag", 500, "--model", model,
                          "--plot", plot], capsys)
    assert status == 1 and model.read_text() == "previous model" and plot.read_bytes() == b"previous plot"


def test_a_write_failing_midway_writes_nothing(data_csv, tmp_path, capsys, monkeypatch):
    model, plot = tmp_path / "m.json", tmp_path / "fit.png"
    model.write_text("previous model")
    real_replace = os.replace

    def failing_replace(source, target):  # the plot moves into place, then the disk is full
        if str(target) == str(model):
            raise OSError(28, "No space left on device")
        real_replace(source, target)

    monkeypatch.setattr(os, "replace", failing_replace)
    status, _, err = run(["identify", data_csv, "--inputs", 1, "--outputs", 3, "--lag", 1, "--model", model,
                          "--plot", plot], capsys)
    assert status == 2 and "--model: cannot write" in err and "nothing was written" in err
    assert model.read_text() == "previous model"
    assert not [p for p in tmp_path.iterdir() if ".partial" in p.name]


def test_lag_with_maxiter_0_says_nothing_converged(data_csv, tmp_path, capsys):
    status, out, err = run(["lag", data_csv, "--inputs", "1-2", "--outputs", "y", "--lags", "1,2", "--modes", "eiv",
                            "--maxiter", 0, "--plot", tmp_path / "lag.png"], capsys)
    assert status == 0, err
    assert "no lag converged within --maxiter 0 iterations" in out
    assert f"note (errors-in-variables): lag 1: {Status.MAXITER.value}" in out  # the solver's account of its status


def test_daisy_that_identified_nothing_writes_nothing(tmp_path, capsys, monkeypatch):
    from ident import daisy_runner
    failed = daisy_runner.ModeResult("eiv", account="identification failed: lra: ValueError: x")
    result = daisy_runner.SetResult("erie", 1, 57, 5, 2, 1, 40, 17, None, {"eiv": failed})
    monkeypatch.setattr(daisy_runner, "run_benchmark", lambda *args, **kwargs: [result])
    out_folder = tmp_path / "out"
    out_folder.mkdir()
    (out_folder / "table.md").write_text("previous table")
    status, _, err = run(["daisy", "erie", "--out", out_folder, "--quiet"], capsys)
    assert status == 1 and "every identification failed" in err and "nothing was written" in err
    assert sorted(p.name for p in out_folder.iterdir()) == ["table.md"]
    assert (out_folder / "table.md").read_text() == "previous table"


def test_daisy_results_are_replaced_all_or_nothing(tmp_path, monkeypatch):
    from ident import daisy_report, daisy_runner
    model = random_system(1, 1, 1, np.random.default_rng(1))
    mode = daisy_runner.ModeResult("eiv", "lra", 1.0, 3, 0.1, True, 90.0, [90.0], 90.0, 91.0, 0.5, 2.0, "", [],
                                   model)
    results = [daisy_runner.SetResult("erie", 1, 57, 5, 2, 1, 40, 17, None, {"eiv": mode})]
    folder = tmp_path / "out"
    daisy_report.write_results(results, folder)
    before = {p.name: p.read_bytes() for p in folder.iterdir()}

    def broken_figure(results, path=None):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(daisy_report, "figure1", broken_figure)
    with pytest.raises(OSError):
        daisy_report.write_results(results, folder)
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before


def test_identify_data_at_an_extreme_scale(data_csv, tmp_path, capsys):
    table = np.loadtxt(data_csv, delimiter=",", skiprows=1)
    np.savetxt(data_csv, 1e200 * table, delimiter=",", header="u1,u2,y", comments="")
    model = tmp_path / "m.json"
    status, out, err = run(["identify", data_csv, "--inputs", "u1,u2", "--outputs", "y", "--lag", 2,
                            "--exact", "inputs", "--model", model, "--plot", tmp_path / "fit.png"], capsys)
    assert status == 0, err
    saved = json.loads(model.read_text())  # valid JSON: an overflowing misfit is null, not Infinity
    assert saved["misfit"] is None and saved["fit"] > 95
    assert "warning: ident: the misfit" in out and "beyond the floating-point range" in out


def test_daisy_workers_and_scheduler_are_checked(tmp_path, capsys, monkeypatch):
    status, _, err = run(["daisy", "erie", "--workers", "0", "--out", tmp_path / "a"], capsys)
    assert status == 2 and "--workers: must be a positive integer, got 0" in err
    status, _, err = run(["daisy", "erie", "--workers", "-2", "--out", tmp_path / "a"], capsys)
    assert status == 2 and "--workers" in err
    status, _, err = run(["daisy", "erie", "--workers", "2", "--scheduler", "tcp://127.0.0.1:9", "--out",
                          tmp_path / "a"], capsys)
    assert status == 2 and "--scheduler: not allowed with argument --workers" in err
    pytest.importorskip("distributed")
    monkeypatch.setattr(cli, "SCHEDULER_TIMEOUT", 1.0)
    status, _, err = run(["daisy", "erie", "--scheduler", "tcp://127.0.0.1:9", "--out", tmp_path / "a"], capsys)
    assert status == 2 and "--scheduler: cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'" in err
    assert not (tmp_path / "a").exists()


def test_daisy_on_two_workers_writes_the_serial_files(tmp_path, capsys):
    pytest.importorskip("distributed")
    if not (SHARED / "erie.dat").is_file():
        pytest.skip(f"the DAISY files are not in {SHARED}")
    common = ["daisy", "erie", "robot_arm", "--data-dir", SHARED, "--no-download", "--quiet", "--maxiter", "50"]
    assert run([*common, "--out", tmp_path / "serial"], capsys)[0] == 0
    status, out, err = run([*common, "--out", tmp_path / "dask", "--workers", "2"], capsys)
    assert status == 0, err
    for name in ("table.md", "table.csv", "results.json", "figure1.png"):
        assert (tmp_path / "serial" / name).read_bytes() == (tmp_path / "dask" / name).read_bytes(), name


# --- output files (issue 32): never an input, never half written, never a temporary file left ---------

IDENTIFY = ["--inputs", "u1,u2", "--outputs", "y", "--lag", 1]


def snapshot(folder: Path) -> dict:
    """Every entry under `folder` with its kind and bytes (links as their target), to compare before and after."""
    entries = {}
    for path in sorted(folder.rglob("*")):
        if path.is_symlink():
            entries[str(path)] = ("link", os.readlink(path))
        elif path.is_file():
            entries[str(path)] = ("file", path.read_bytes(), oct(path.stat().st_mode))
        else:
            entries[str(path)] = ("other", path.stat().st_mode)
    return entries


def refused_before_writing(argv, capsys, folder: Path, *words: str) -> None:
    before = snapshot(folder)
    status, out, err = run(argv, capsys)
    assert status == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert all(word in err for word in words), err
    assert snapshot(folder) == before


def fake_daisy_folder(tmp_path: Path) -> Path:
    """A data folder holding a file named as DAISY's erie.dat (only compared, never read)."""
    folder = tmp_path / "daisy-data"
    folder.mkdir()
    (folder / "erie.dat").write_text("1 2 3\n")
    return folder


@pytest.mark.parametrize("case", ["model is the data", "model is the npz data", "plot is the data",
                                  "model through ..", "model is a link to the data", "model is a hard link to the data",
                                  "plot is a link to the data"])
def test_identify_never_writes_over_its_data(case, data_csv, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # default outputs land in tmp_path, which is compared
    data, option, output = data_csv, "--model", data_csv
    if case == "model is the npz data":
        data = output = npz_data(tmp_path)
    elif case == "plot is the data":
        data = output = data_csv.rename(tmp_path / "plant.svg")
        option = "--plot"
    elif case == "model through ..":
        (tmp_path / "sub").mkdir()
        output = tmp_path / "sub" / ".." / data_csv.name
    elif case in ("model is a link to the data", "plot is a link to the data"):
        output = tmp_path / ("link.json" if case.startswith("model") else "link.png")
        output.symlink_to(data_csv)
        option = "--model" if case.startswith("model") else "--plot"
    elif case == "model is a hard link to the data":
        output = tmp_path / "hard.json"
        os.link(data_csv, output)
    columns = [] if data.suffix == ".npz" else IDENTIFY[:4]
    refused_before_writing(["identify", data, *columns, "--lag", 1, option, output], capsys, tmp_path,
                           f"{option}: {output} is the data file {data}", "nothing was written")


@pytest.mark.parametrize("link", [False, True])
def test_identify_refuses_one_file_for_model_and_plot(link, data_csv, tmp_path, capsys):
    model = plot = tmp_path / "out.svg"
    if link:  # a link to a file not yet written is the same file too
        plot = tmp_path / "fit.svg"
        plot.symlink_to(model)
    refused_before_writing(["identify", data_csv, *IDENTIFY, "--model", model, "--plot", plot], capsys, tmp_path,
                           "--model and --plot name the same file", "nothing was written")


def test_lag_never_writes_its_plot_over_its_data(data_csv, tmp_path, capsys):
    data = data_csv.rename(tmp_path / "plant.png")
    refused_before_writing(["lag", data, "--inputs", "1-2", "--outputs", "y", "--plot", data], capsys, tmp_path,
                           f"--plot: {data} is the data file {data}")
    link = tmp_path / "lag.png"
    link.symlink_to(data)
    refused_before_writing(["lag", data, "--inputs", "1-2", "--outputs", "y", "--plot", link], capsys, tmp_path,
                           f"--plot: {link} is the data file {data}")


def test_lag_and_daisy_never_write_over_a_daisy_file(tmp_path, capsys):
    data_dir = fake_daisy_folder(tmp_path)
    link = tmp_path / "erie.png"
    link.symlink_to(data_dir / "erie.dat")
    refused_before_writing(["lag", "erie", "--data-dir", data_dir, "--no-download", "--plot", link], capsys, tmp_path,
                           f"--plot: {link} is the DAISY file of erie")
    out = tmp_path / "out"
    out.mkdir()
    (out / "table.csv").symlink_to(data_dir / "erie.dat")
    refused_before_writing(["daisy", "erie", "--data-dir", data_dir, "--no-download", "--quiet", "--out", out], capsys,
                           tmp_path, f"--out: {out / 'table.csv'} is the DAISY file of erie")


@pytest.mark.parametrize("command", ["identify", "lag", "daisy"])
def test_an_output_that_is_a_fifo_or_a_folder_is_not_replaced(command, data_csv, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # default outputs land in tmp_path, which is compared
    fifo = tmp_path / ("results" if command == "daisy" else "out.png")
    os.mkfifo(fifo if command != "daisy" else tmp_path / "table.md")
    if command == "identify":
        argv = ["identify", data_csv, *IDENTIFY, "--model", fifo, "--plot", tmp_path / "fit.png"]
    elif command == "lag":
        argv = ["lag", data_csv, "--inputs", "1-2", "--outputs", "y", "--plot", fifo]
    else:
        argv = ["daisy", "erie", "--quiet", "--out", tmp_path]
        fifo = tmp_path / "table.md"
    refused_before_writing(argv, capsys, tmp_path, f"{fifo} is not a regular file (a FIFO, device or socket)")
    (tmp_path / "folder.json").mkdir()
    if command == "identify":
        refused_before_writing(["identify", data_csv, *IDENTIFY, "--model", tmp_path / "folder.json"], capsys, tmp_path,
                               "--model: ", "folder.json is a folder")


def test_a_read_only_output_is_not_replaced(data_csv, tmp_path, capsys):
    model = tmp_path / "m.json"
    model.write_text("kept")
    model.chmod(0o444)
    refused_before_writing(["identify", data_csv, *IDENTIFY, "--model", model, "--plot", tmp_path / "fit.png"], capsys,
                           tmp_path, f"--model: {model} is read-only")


def read_only_file_system(monkeypatch, when: str) -> None:
    """Make the writes fail as on a read-only file system: at once ("before") or after the checks ("after")."""
    def refuse(*args, **kwargs):
        raise OSError(30, "Read-only file system", str(args[0]) if args else "")

    if when == "before":
        monkeypatch.setattr(tempfile, "mkstemp", refuse)
    else:
        monkeypatch.setattr(Path, "write_text", lambda self, *a, **k: refuse(self))
        monkeypatch.setattr(os, "replace", refuse)


@pytest.mark.parametrize("when", ["before", "after"])
def test_a_read_only_file_system_is_one_line_naming_the_target(when, data_csv, tmp_path, capsys, monkeypatch):
    model, plot = tmp_path / "m.json", tmp_path / "fit.png"
    model.write_text("previous model")
    before = snapshot(tmp_path)
    read_only_file_system(monkeypatch, when)
    status, _, err = run(["identify", data_csv, *IDENTIFY, "--model", model, "--plot", plot], capsys)
    monkeypatch.undo()
    assert status != 0 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert "Read-only file system" in err and (f"--model: cannot write {model}" in err or
                                                f"--plot: cannot write {plot}" in err), err
    assert ".partial" not in err and ".ident-" not in err
    assert snapshot(tmp_path) == before


def daisy_results(fit: float = 90.0):
    from ident import daisy_runner
    model = random_system(1, 1, 1, np.random.default_rng(1))
    mode = daisy_runner.ModeResult("eiv", "lra", 1.0, 3, 0.1, True, fit, [fit], fit, 91.0, 0.5, 2.0, "", [],
                                   model)
    return [daisy_runner.SetResult("erie", 1, 57, 5, 2, 1, 40, 17, None, {"eiv": mode})]


@pytest.mark.parametrize("new_folder", [False, True])
def test_daisy_on_a_read_only_file_system_names_out(new_folder, tmp_path, capsys, monkeypatch):
    from ident import daisy_runner
    out = tmp_path / "new" / "out" if new_folder else tmp_path
    before = snapshot(tmp_path)
    read_only_file_system(monkeypatch, "after")
    monkeypatch.setattr(daisy_runner, "run_benchmark", lambda *args, **kwargs: daisy_results())
    status, _, err = run(["daisy", "erie", "--quiet", "--out", out], capsys)
    monkeypatch.undo()
    assert status != 0 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert f"--out: cannot write {out} (Read-only file system)" in err and ".partial" not in err, err
    assert snapshot(tmp_path) == before  # no file, no temporary folder, no folder made for nothing


def test_daisy_writes_exactly_the_files_it_checked(tmp_path, capsys, monkeypatch):
    from ident import daisy_runner
    monkeypatch.setattr(daisy_runner, "run_benchmark", lambda *args, **kwargs: daisy_results())
    status, out, err = run(["daisy", "erie", "--quiet", "--out", tmp_path / "out"], capsys)
    assert status == 0, err
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == sorted(cli.DAISY_FILES)
    assert f"wrote {tmp_path / 'out' / 'table.md'}" in out


def test_a_file_not_checked_before_the_run_is_not_moved(tmp_path):
    from ident import output_files
    folder = tmp_path / "new"

    def writer(staging):
        (staging / "table.md").write_text("new")
        (staging / "unexpected.txt").write_text("?")

    with pytest.raises(RuntimeError, match=r"\['unexpected.txt'\] were written but not checked"):
        output_files.write_into_folder(folder, "--out", ("table.md",), writer)
    assert not folder.exists()


def test_an_interrupt_while_writing_leaves_the_previous_files(data_csv, tmp_path, capsys, monkeypatch):
    model, plot = tmp_path / "m.json", tmp_path / "fit.png"
    model.write_text("previous model"), plot.write_bytes(b"previous plot")
    before = snapshot(tmp_path)

    def interrupted_plot(path, *args):
        Path(path).write_bytes(b"half a pl")
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_plot_fit", interrupted_plot)
    status, _, err = run(["identify", data_csv, *IDENTIFY, "--model", model, "--plot", plot], capsys)
    assert status == 130 and "interrupted" in err
    assert snapshot(tmp_path) == before


def test_an_interrupt_between_the_moves_puts_the_first_file_back(data_csv, tmp_path, capsys, monkeypatch):
    model, plot = tmp_path / "m.json", tmp_path / "fit.png"
    model.write_text("previous model"), plot.write_bytes(b"previous plot")
    before = snapshot(tmp_path)
    real_replace = os.replace

    def replace(source, target):  # the plot moved into place, then Ctrl-C
        if Path(target) == model:
            raise KeyboardInterrupt
        real_replace(source, target)

    monkeypatch.setattr(os, "replace", replace)
    status, _, err = run(["identify", data_csv, *IDENTIFY, "--model", model, "--plot", plot], capsys)
    assert status == 130 and "interrupted" in err
    assert snapshot(tmp_path) == before


def test_a_failed_move_puts_back_a_new_plot_too(data_csv, tmp_path, capsys, monkeypatch):
    model, plot = tmp_path / "m.json", tmp_path / "fit.png"
    model.write_text("previous model")  # no plot before: the new one is removed again
    before = snapshot(tmp_path)
    real_replace = os.replace

    def replace(source, target):
        if Path(target) == model:
            raise OSError(28, "No space left on device")
        real_replace(source, target)

    monkeypatch.setattr(os, "replace", replace)
    status, _, err = run(["identify", data_csv, *IDENTIFY, "--model", model, "--plot", plot], capsys)
    assert status == 2 and f"--model: cannot write {model} (No space left on device); nothing was written" in err
    assert snapshot(tmp_path) == before


def test_an_interrupted_daisy_write_keeps_the_previous_results(tmp_path, capsys, monkeypatch):
    from ident import daisy_report, daisy_runner
    monkeypatch.setattr(daisy_runner, "run_benchmark", lambda *args, **kwargs: daisy_results())
    assert run(["daisy", "erie", "--quiet", "--out", tmp_path], capsys)[0] == 0
    before = snapshot(tmp_path)

    def interrupted(*args, **kwargs):  # the four tables are written, then Ctrl-C before the run log
        raise KeyboardInterrupt

    monkeypatch.setattr(daisy_report, "run_log", interrupted)
    monkeypatch.setattr(daisy_runner, "run_benchmark", lambda *args, **kwargs: daisy_results(fit=80.0))
    status, _, err = run(["daisy", "erie", "--quiet", "--out", tmp_path], capsys)
    assert status == 130 and snapshot(tmp_path) == before


def test_an_output_link_is_written_through_and_permissions_are_kept(data_csv, tmp_path, capsys):
    elsewhere = tmp_path / "models"
    elsewhere.mkdir()
    (elsewhere / "m.json").write_text("previous model")
    (elsewhere / "m.json").chmod(0o640)
    link = tmp_path / "m.json"
    link.symlink_to(elsewhere / "m.json")
    plot = tmp_path / "fit.png"
    status, _, err = run(["identify", data_csv, *IDENTIFY, "--model", link, "--plot", plot], capsys)
    assert status == 0, err
    assert link.is_symlink() and "A" in json.loads((elsewhere / "m.json").read_text())
    assert (elsewhere / "m.json").stat().st_mode & 0o777 == 0o640
    mask = os.umask(0o022)
    os.umask(mask)
    assert plot.stat().st_mode & 0o777 == 0o666 & ~mask  # a new file: the umask's, not a temporary file's 0o600
    assert not [p for p in tmp_path.rglob(".*")]  # no temporary file, no probe, no backup


@pytest.mark.parametrize("command", ["identify", "lag"])
def test_a_data_file_that_is_a_fifo_is_refused_without_blocking(command, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # default outputs land in tmp_path, which is compared
    fifo = tmp_path / "data.csv"
    os.mkfifo(fifo)
    argv = [command, fifo, "--inputs", 1, "--outputs", 2] + (["--lag", 1] if command == "identify" else [])
    refused_before_writing(argv, capsys, tmp_path, f"{fifo} is not a regular file (a FIFO, device or socket)")


# --- issue 32: an interrupted daisy run keeps the sets it finished, beside the complete results ----------

def test_an_interrupted_daisy_run_saves_its_finished_sets_beside_the_results(tmp_path, capsys, monkeypatch):
    from ident import daisy_runner
    model = random_system(1, 1, 1, np.random.default_rng(1))
    mode = daisy_runner.ModeResult("eiv", "lra", 1.0, 3, 0.1, True, 90.0, [90.0], 90.0, 91.0, 0.5, 2.0, "", [],
                                   model)
    finished = [daisy_runner.SetResult("erie", 1, 57, 5, 2, 1, 40, 17, None, {"eiv": mode})]

    def interrupted(*args, **kwargs):
        raise daisy_runner.BenchmarkInterrupted(finished, 3)

    monkeypatch.setattr(daisy_runner, "run_benchmark", interrupted)
    out_folder = tmp_path / "out"
    out_folder.mkdir()
    (out_folder / "table.md").write_text("previous table")
    status, _, err = run(["daisy", "--out", out_folder, "--quiet"], capsys)
    assert status == 130 and "the 1 of 3 sets that had finished are in" in err
    assert (out_folder / "table.md").read_text() == "previous table"  # the complete results are untouched
    saved = out_folder / cli.INTERRUPTED_FOLDER
    assert sorted(p.name for p in saved.iterdir()) == sorted(cli.DAISY_FILES)
    assert "erie" in (saved / "table.md").read_text()
    monkeypatch.setattr(daisy_runner, "run_benchmark",
                        lambda *a, **k: (_ for _ in ()).throw(daisy_runner.BenchmarkInterrupted([], 3)))
    status, _, err = run(["daisy", "--out", tmp_path / "other", "--quiet"], capsys)
    assert status == 130 and "before any set had finished" in err and not (tmp_path / "other").exists()


# --- issue 31, roles by name: --exact counts the file's columns, as --inputs and --outputs do --------

def test_exact_columns_are_the_files_columns_and_are_printed_by_name(data_csv, tmp_path, capsys):
    """--inputs 2 --outputs 3 --exact 2: the file's column 2 (u2, counted from 1), the only input, not
    w's second variable (the output); the printout names it as the file does."""
    model = tmp_path / "m.json"
    status, out, err = run(["identify", data_csv, "--inputs", "2", "--outputs", "3", "--lag", "2", "--exact", "2",
                            "--model", model, "--plot", tmp_path / "fit.png"], capsys)
    assert status == 0, err
    assert "exact: u2" in out
    assert json.loads(model.read_text())["exact"] == [0]  # the model file: positions in [inputs outputs]
    status, out, err = run(["identify", data_csv, "--inputs", "2", "--outputs", "3", "--lag", "2", "--exact", "u2",
                            "--model", model, "--plot", tmp_path / "fit.png"], capsys)
    assert status == 0 and "exact: u2" in out, err


def test_exact_columns_not_chosen_are_refused_in_one_line(data_csv, tmp_path, capsys):
    status, out, err = run(["identify", data_csv, "--inputs", "2", "--outputs", "3", "--lag", "2", "--exact", "1",
                            "--model", tmp_path / "m.json", "--plot", tmp_path / "fit.png"], capsys)
    assert status == 2 and len(err.strip().splitlines()) == 1, err
    assert "--exact: column(s) 'u1' are neither --inputs nor --outputs" in err


def test_the_help_says_how_columns_are_counted(capsys):
    status, out, _ = run(["identify", "--help"], capsys)
    out = " ".join(out.split())
    assert status == 0 and "counted from 1" in out and "columns of the file as for --inputs" in out


@pytest.mark.parametrize("spec, message", [
    ("0", "--inputs: columns are counted from 1 to 3 (the file's columns); got '0'"),
    ("1:3", "--inputs: '1:3' looks like a Python slice; columns are counted from 1 and a range is written a-b"),
    ("2-9", "--inputs: columns are counted from 1 to 3 (the file's columns); got '2-9'"),
    ("-1", "--inputs: '-1' is neither a column number, a range a-b nor a column name"),
])
def test_column_numbers_count_from_one_and_slices_are_refused(data_csv, capsys, spec, message):
    """Columns are counted from 1 as the file's (cut, awk, DAISY's descriptions); the old 0-based
    slice syntax is refused with the new spelling rather than read with another meaning."""
    status, _, err = run(["identify", data_csv, "--inputs", spec, "--outputs", "y", "--lag", "1"], capsys)
    assert status == 2 and message in err and len(err.strip().splitlines()) == 1, err


def test_a_range_of_column_numbers_includes_both_ends(data_csv, tmp_path, capsys):
    """--inputs 1-2 is the file's first two columns (u1, u2), the same model as naming them."""
    fits = []
    for spec in ("1-2", "u1,u2"):
        status, out, err = run(["identify", data_csv, "--inputs", spec, "--outputs", "3", "--lag", "1",
                                "--model", tmp_path / "m.json", "--plot", tmp_path / "fit.png"], capsys)
        assert status == 0, err
        fits.append(json.loads((tmp_path / "m.json").read_text()))
    assert fits[0]["inputs"] == fits[1]["inputs"] == ["u1", "u2"]


# --- issue 31 point 7 (the small edges): an option must be spelled whole ----------------------------------

@pytest.mark.parametrize("argv, abbreviation", [
    (["identify", "DATA", "--lag", 1, "--n", 1], "--n"),            # was read as --no-center
    (["identify", "DATA", "--lag", 1, "--exa", "inputs"], "--exa"),  # was read as --exact
    (["identify", "DATA", "--lag", 1, "--hold", 0.5], "--hold"),    # was read as --holdout
    (["lag", "DATA", "--inputs", "u1,u2", "--outputs", "y", "--max", 5], "--max"),
    (["daisy", "erie", "--work", 2], "--work"),
    (["--trace", "identify", "DATA", "--lag", 1], "--trace"),
])
def test_an_abbreviated_option_is_refused(argv, abbreviation, data_csv, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = [data_csv if a == "DATA" else a for a in argv]
    before = snapshot(data_csv.parent)
    status, out, err = run(argv, capsys)
    assert status == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert f"unrecognized arguments: {abbreviation}" in err
    assert snapshot(data_csv.parent) == before  # nothing was run, nothing written


def test_daisy_workers_without_dask_says_what_works_from_a_clone(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed now raises ImportError
    status, _, err = run(["daisy", "erie", "--workers", 1, "--data-dir", SHARED, "--no-download", "--quiet",
                          "--out", tmp_path / "out"], capsys)
    assert status == 2 and len(err.strip().splitlines()) == 1, err
    assert "--workers: running jobs on Dask needs dask.distributed" in err
    assert "pip install 'dask[distributed]>=2024.1'" in err and "pip install -e '.[distributed]'" in err
    assert not (tmp_path / "out").exists()


def test_daisy_on_two_workers_prints_nothing_of_dask(tmp_path):
    """Dask's own log lines (nanny warnings on start and shutdown) and its warning that port 8787 is
    taken (held here on purpose, as another cluster would) are not printed (issue 31)."""
    pytest.importorskip("distributed")
    if not (SHARED / "erie.dat").is_file():
        pytest.skip(f"the DAISY files are not in {SHARED}")
    import socket

    with contextlib.ExitStack() as stack:
        dashboard_port = stack.enter_context(socket.socket())
        with contextlib.suppress(OSError):  # taken already: by another cluster, as it should be
            dashboard_port.bind(("", 8787))
            dashboard_port.listen()
        done = subprocess.run([sys.executable, "-m", "ident", "daisy", "erie", "--workers", "2", "--data-dir", SHARED,
                               "--no-download", "--quiet", "--maxiter", "5", "--out", tmp_path / "out"],
                              capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stderr == "", done.stderr
    assert (tmp_path / "out" / "table.md").is_file()


# --- issue 31, the lag choice and time axes: lag --plot marks the chosen lags, the CLI chooses the lag
# choose_lag chooses on the same centred data, identify's fit plot is against time -----------------------
def test_lag_plot_marks_the_lag_chosen_in_each_mode(data_csv, tmp_path, capsys, monkeypatch):
    drawn = {}
    real = cli.plot_lag_curves

    def recording(curves, path, **options):
        drawn.update(options, figure=real(curves, path, **options))
        return drawn["figure"]

    monkeypatch.setattr(cli, "plot_lag_curves", recording)
    status, out, err = run(["lag", data_csv, "--inputs", "1-2", "--outputs", "y", "--lags", "1-3",
                            "--plot", tmp_path / "lag.png"], capsys)
    assert status == 0, err
    chosen = {mode: int(line.split(": ")[1].split()[0]) for mode in ("OE", "EIV") for line in out.splitlines()
              if line.startswith(f"chosen lag ({mode}, ")}
    assert set(chosen) == {"OE", "EIV"}
    assert sorted(drawn["chosen"].values()) == sorted(set(chosen.values()))
    legend = [text.get_text() for text in drawn["figure"].axes[0].get_legend().get_texts()]
    for mode, lag in chosen.items():
        assert any(label.startswith("chosen lag (") and mode in label.split("(")[1] and label.endswith(f"(ell = {lag})")
                   for label in legend), legend


def test_lag_marks_put_modes_with_one_lag_together():
    assert cli.lag_marks(5, {"oe": 3, "eiv": 3}) == {"lag of Table 1": 5, "chosen lag (OE, EIV)": 3}
    assert cli.lag_marks(None, {"oe": 2, "eiv": None}) == {"chosen lag (OE)": 2}


def test_the_fit_plot_is_against_time_at_dt(tmp_path):
    from ident.validation import validate
    from ident.representations import make_ss
    model = make_ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], 0.05)
    u = np.sin(np.arange(30.0))[:, None]
    y = simulate(model, u)
    result = validate(model, u, y)
    figure = cli._plot_fit(tmp_path / "fit.png", y, result, ["y"], "the last 30 samples (30%)", 70, 0.05)
    assert figure.axes[-1].get_xlabel() == "time (s): the last 30 samples (30%)"
    np.testing.assert_allclose(figure.axes[0].get_lines()[0].get_xdata(), 0.05 * np.arange(70, 100))
    figure = cli._plot_fit(tmp_path / "fit.png", y, result, ["y"], "the last 30 samples (30%)", 70)
    assert figure.axes[-1].get_xlabel() == "sample: the last 30 samples (30%)"
    np.testing.assert_allclose(figure.axes[0].get_lines()[0].get_xdata(), np.arange(70, 100))


DAISY_SETS = [dataset.name for dataset in __import__("ident.daisy").daisy.table1()]  # the 17 sets of Table 1


@pytest.mark.slow
@pytest.mark.parametrize("name", DAISY_SETS)
def test_the_command_line_chooses_the_lag_choose_lag_chooses(name, tmp_path, capsys):
    """`lag SET` and choose_lag on the identification part the command line centres and splits (minutes in all)."""
    from ident import daisy, daisy_runner
    from ident.lag_arguments import CHOOSE_LAG_HOLDOUT, lag_refusal
    from ident.validation import choose_lag, split_for_validation
    if not (SHARED / f"{name}.dat").is_file():
        pytest.skip(f"the DAISY files are not in {SHARED}")
    info = daisy.dataset(name)
    status, out, err = run(["lag", name, "--data-dir", SHARED, "--no-download", "--lags", "1-3", "--maxiter", "20",
                            "--plot", tmp_path / "lag.png"], capsys)
    assert status == 0, err
    u, y = daisy.load(name, SHARED, download_missing=False)
    w = split_for_validation(u, y, daisy_runner.HOLDOUT).identification
    judged = [lag for lag in (1, 2, 3) if lag_refusal(w, info.m, lag, CHOOSE_LAG_HOLDOUT) is None]  # erie: 1, 2
    for mode, exct in (("OE", list(range(info.m))), ("EIV", None)):
        line = next(line for line in out.splitlines() if line.startswith((f"chosen lag ({mode}, ", f"no lag chosen ({mode})")))
        choice = choose_lag(w, info.m, judged, exct=exct, maxiter=20)
        assert line.split(": ")[1].split()[0] == str(choice.ell), (mode, line)


# --- affine identification: identify's --offset {mean,fit,none} and its alias --no-center (issue 31) ---
def offset_run(data_csv, tmp_path, capsys, *options):
    model = tmp_path / "m.json"
    status, out, err = run(["identify", data_csv, "--inputs", "u1,u2", "--outputs", "y", "--lag", 2,
                            "--model", model, "--plot", tmp_path / "fit.png", *options], capsys)
    return status, out, err, (json.loads(model.read_text()) if status == 0 else None)


def test_identify_offset_fit_is_ident_with_offset_true(data_csv, tmp_path, capsys):
    from ident import ident
    status, out, err, saved = offset_run(data_csv, tmp_path, capsys, "--offset", "fit")
    assert status == 0, err
    w = np.loadtxt(data_csv, delimiter=",", skiprows=1)[:210]
    sysh, info, _, _ = ident(w, 2, 2, offset=True)
    assert saved["misfit"] == pytest.approx(info.M, rel=1e-8)
    assert np.allclose(saved["means"]["inputs"], info.offset.inputs, rtol=1e-12, atol=0)
    assert np.allclose(saved["means"]["outputs"], info.offset.outputs, rtol=1e-8, atol=0)
    assert saved["fit"] > 95  # validated with the offset applied


def test_identify_offset_mean_is_the_default_and_none_is_no_center(data_csv, tmp_path, capsys):
    _, _, _, default = offset_run(data_csv, tmp_path, capsys)
    _, _, _, mean = offset_run(data_csv, tmp_path, capsys, "--offset", "mean")
    _, _, _, none = offset_run(data_csv, tmp_path, capsys, "--offset", "none")
    _, _, _, alias = offset_run(data_csv, tmp_path, capsys, "--no-center")
    assert default["misfit"] == pytest.approx(mean["misfit"], rel=1e-12)
    assert default["means"]["outputs"][0] == pytest.approx(10, abs=1)
    assert none["means"]["outputs"] == [0.0] and alias["means"] == none["means"]
    assert alias["misfit"] == pytest.approx(none["misfit"], rel=1e-12)


@pytest.mark.parametrize("options, words", [
    (["--offset", "fit", "--no-center"], "--no-center is --offset none, which contradicts --offset fit"),
    (["--offset", "fit", "--zero-initial"], "--zero-initial and --offset fit"),
    (["--offset", "centre"], "--offset: invalid choice: 'centre'"),
])
def test_identify_offset_bad_input(options, words, data_csv, tmp_path, capsys):
    status, out, err, _ = offset_run(data_csv, tmp_path, capsys, *options)
    assert status == 2 and words in err and "Traceback" not in err
    assert len(err.strip().splitlines()) <= 2  # usage line and one message (argparse's choices: usage first)


# --- issue 31: lag chooses among the lags choose_lag can judge, and names the others -----------------------

def test_lag_chooses_among_the_lags_it_can_judge_and_names_the_rest(data_csv, tmp_path, capsys):
    """Lag 40 is on the curve (210 identification samples) but too long for choose_lag's estimation
    part (147 samples): the choice is among the others and its line names 40, as destill's 5-8."""
    status, out, err = run(["lag", data_csv, "--inputs", "1-2", "--outputs", "y", "--lags", "1,2,40", "--modes", "oe",
                            "--maxiter", 5, "--plot", tmp_path / "lag.png"], capsys)
    assert status == 0, err
    line = next(line for line in out.splitlines() if line.startswith("chosen lag (OE"))
    assert line.endswith("; lag 40 too long to judge on these data)") and " 40:" not in line, line

# ---- complete and forecast (29-completion-and-forecasting.md) ----
@pytest.fixture
def completion_files(data_csv, tmp_path, capsys):
    """A model identified from data_csv, a copy of its first 100 samples with gaps, a past and a future."""
    from ident.__main__ import main as full_main
    model = tmp_path / "m.json"
    assert full_main(["identify", str(data_csv), "--inputs", "u1,u2", "--outputs", "y", "--lag", "2",
                      "--model", str(model), "--plot", str(tmp_path / "fit.png")]) == 0
    w = np.loadtxt(data_csv, delimiter=",", skiprows=1)
    gappy = w[:100].copy()
    gaps = np.random.default_rng(6).random(gappy.shape) < 0.2
    gappy[gaps] = np.nan
    paths = {"model": model, "gappy": tmp_path / "gappy.csv", "past": tmp_path / "past.csv",
             "future": tmp_path / "future.csv"}
    np.savetxt(paths["gappy"], gappy, delimiter=",", header="u1,u2,y", comments="")
    np.savetxt(paths["past"], w[200:250], delimiter=",", header="u1,u2,y", comments="")
    np.savetxt(paths["future"], w[250:, [1, 0]], delimiter=",", header="u2,u1", comments="")  # by name, any order
    capsys.readouterr()
    return paths, w, gaps


def run_full(argv, capsys) -> tuple[int, str, str]:
    from ident.__main__ import main as full_main
    status = full_main([str(a) for a in argv])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def test_complete_and_forecast_on_the_command_line(completion_files, tmp_path, capsys):
    paths, w, gaps = completion_files
    out, plot = tmp_path / "filled.csv", tmp_path / "filled.png"
    status, printed, err = run_full(["complete", paths["gappy"], "--model", paths["model"], "--out", out, "--plot", plot],
                                    capsys)
    assert status == 0, err
    assert f"{gaps.sum()} missing value(s) filled" in printed and plot.stat().st_size > 0
    filled = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.array_equal(filled[~gaps], w[:100][~gaps])  # the observed values as they were
    assert np.abs(filled[:, 2] - w[:100, 2])[gaps[:, 2]].max() < 0.2 * np.abs(w[:, 2] - w[:, 2].mean()).max()
    out = tmp_path / "ahead.csv"
    status, printed, err = run_full(["forecast", paths["past"], "--model", paths["model"], "--future", paths["future"],
                                     "--out", out], capsys)
    assert status == 0, err
    ahead = np.loadtxt(out, delimiter=",", skiprows=1)
    assert ahead.shape == (50, 3) and np.array_equal(ahead[:, :2], w[250:, :2])
    assert np.linalg.norm(ahead[:, 2] - w[250:, 2]) < 0.1 * np.linalg.norm(w[250:, 2] - w[250:, 2].mean())


@pytest.mark.parametrize("argv, words", [
    (["forecast", "{past}", "--model", "{model}"], "the following arguments are required: --future"),
    (["forecast", "{past}", "--model", "{model}", "--future", "{gappy}"], "--future: .* holds missing or infinite values"),
    (["complete", "{future}", "--model", "{model}"], "data: .* has columns u2, u1; expected the model's signals u1, u2, y"),
    (["complete", "{gappy}", "--model", "{gappy}"], "--model: cannot read the model file"),
    (["complete", "{gappy}", "--model", "{model}", "--out", "{gappy}"], "--out"),
    (["complete", "{gappy}", "--model", "{model}", "--plot", "{dir}/p.unknown"], "--plot"),
    (["forecast", "{short}", "--model", "{model}", "--future", "{future}"], "past: .* has 1 samples, fewer than the lag 2"),
])
def test_bad_options_of_complete_and_forecast_are_one_line(completion_files, tmp_path, capsys, argv, words):
    paths, w, _ = completion_files
    short = tmp_path / "short.csv"
    np.savetxt(short, w[:1], delimiter=",", header="u1,u2,y", comments="")
    names = {key: str(value) for key, value in paths.items()} | {"short": str(short), "dir": str(tmp_path)}
    status, _, err = run_full([item.format(**names) for item in argv], capsys)
    assert status == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert re.search(words, err), err

# --- identify --uncertainty, --stable, --margin (issue 34) ---

def test_identify_prints_the_intervals_and_the_price_of_stability(data_csv, tmp_path, capsys):
    status, out, err = run(["identify", data_csv, "--inputs", "u1,u2", "--outputs", "y", "--lag", 2, "--exact", "inputs",
                            "--uncertainty", "--stable", "--model", tmp_path / "m.json", "--plot", tmp_path / "f.png"], capsys)
    assert status == 0, err
    assert "95 % intervals (first order; noise variance" in out
    assert out.count("  pole ") == 2 and "gain u1 -> y:" in out and "gain u2 -> y:" in out
    assert "stable: spectral radius" in out and "(the optimum was within the bound)" in out


@pytest.mark.parametrize("options, words", [
    (["--stable", "--margin", "0"], "argument --margin: must be a number in (0, 1), got 0"),
    (["--stable", "--margin", "wide"], "argument --margin: must be a number in (0, 1), got 'wide'"),
    (["--uncertainty", "--offset", "fit"], "--uncertainty and --offset fit: not available together yet"),
    (["--stable", "--offset", "fit"], "--stable and --offset fit: not available together yet"),
])
def test_identify_refuses_bad_error_bar_options_in_one_line(options, words, data_csv, tmp_path, capsys):
    status, out, err = run(["identify", data_csv, "--inputs", "u1,u2", "--outputs", "y", "--lag", 2, *options,
                            "--model", tmp_path / "m.json", "--plot", tmp_path / "f.png"], capsys)
    assert status == 2 and words in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
