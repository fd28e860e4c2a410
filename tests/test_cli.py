"""ident.cli: identify, daisy and lag through main(argv); usage errors are one line with exit status 2."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ident import cli
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
    assert "identified from 210 samples" in out and "exact: 0, 1" in out
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
    (["identify", "{csv}", "--inputs", "0", "--outputs", "2"], "required: --lag"),
    (["identify", "{csv}", "--inputs", "0", "--outputs", "2", "--lag", "two"], "invalid int value"),
    (["identify", "{csv}", "--inputs", "0", "--outputs", "2", "--lag", "-1"], "--lag must be"),
    (["identify", "{csv}", "--inputs", "0", "--outputs", "9", "--lag", "1"], "--outputs: columns must be among 0..2"),
    (["identify", "{csv}", "--inputs", "speed", "--outputs", "2", "--lag", "1"], "'speed' is neither"),
    (["identify", "{csv}", "--inputs", "0", "--outputs", "0", "--lag", "1"], "share columns"),
    (["identify", "{csv}", "--outputs", "2", "--lag", "1"], "--inputs and --outputs are required"),
    (["identify", "{csv}", "--inputs", "0", "--outputs", "2", "--lag", "1", "--holdout", "1.5"], "--holdout"),
    (["identify", "missing.csv", "--inputs", "0", "--outputs", "2", "--lag", "1"], "does not exist"),
    (["identify", "{csv}", "--inputs", "0", "--outputs", "2", "--lag", "1", "--bogus"], "unrecognized arguments"),
    (["frobnicate"], "invalid choice"),
    (["daisy", "nowhere"], "unknown data set(s) nowhere"),
    (["daisy", "--modes", "ml"], "invalid choice"),
    (["lag", "nowhere"], "neither a data file nor a DAISY data set"),
    (["lag", "{csv}", "--lags", "a-b", "--inputs", "0", "--outputs", "2"], "--lags must look like"),
])
def test_bad_arguments_exit_2_with_one_line(argv, expected, data_csv, capsys):
    status, out, err = run([a.replace("{csv}", str(data_csv)) for a in argv], capsys)
    assert status == 2
    assert len(err.strip().splitlines()) == 1 and expected in err and "Traceback" not in err
    assert err.startswith("python -m ident")


def test_a_file_that_is_not_a_table(tmp_path, capsys):
    bad = tmp_path / "notes.csv"
    bad.write_text("a,b\n1,2\nthree,4\n")
    status, _, err = run(["identify", bad, "--inputs", "a", "--outputs", "b", "--lag", "1"], capsys)
    assert status == 2 and "not a numeric table" in err and len(err.strip().splitlines()) == 1


def test_an_impossible_identification_exits_1_with_one_line(data_csv, capsys):
    status, _, err = run(["identify", data_csv, "--inputs", "0", "--outputs", "2", "--lag", "500"], capsys)
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
    status, out, err = run(["lag", data_csv, "--inputs", "0:2", "--outputs", "y", "--lags", "1-3", "--modes", "oe",
                            "--plot", plot], capsys)
    assert status == 0, err
    lines = out.splitlines()
    assert lines[1] == "lag | OE misfit | OE fit %" and len(lines) >= 5 and plot.stat().st_size > 1000


def test_daisy_and_lag_on_a_data_set(tmp_path, capsys):
    if not (SHARED / "erie.dat").is_file():
        pytest.skip(f"the DAISY files are not in {SHARED}")
    status, out, err = run(["daisy", "erie", "--data-dir", SHARED, "--no-download", "--out", tmp_path / "out",
                            "--quiet", "--starts", "lra", "--maxiter", "30"], capsys)
    assert status == 0, err
    assert "mean validation fit over 1 sets" in out and (tmp_path / "out" / "figure1.png").is_file()
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
