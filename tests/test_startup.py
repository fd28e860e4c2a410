"""Start-up: `import ident` and the command line's help load neither python-control nor matplotlib
nor pandas (they take seconds to import; they are imported when first needed). The time itself is
measured by benchmarks/bench_import.py, not here."""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("control", "matplotlib", "pandas", "scipy.signal", "scipy.stats")


def modules_loaded_by(code: str) -> list[str]:
    """The heavy modules present in sys.modules after running `code` in a fresh interpreter."""
    probe = f"{code}\nimport json, sys\nprint(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    out = subprocess.run([sys.executable, "-c", probe], check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


@pytest.mark.parametrize("code", [
    "import ident",
    "from ident import ident, misfit, compare, resid, validate, fit_percent, misfit_vs_lag, load_model",
    "import ident.cli, ident.__main__, ident.validation, ident.daisy_runner, ident.daisy_report",
    "import contextlib, io\nfrom ident.__main__ import main\n"
    "with contextlib.redirect_stdout(io.StringIO()): main(['--help']); main(['identify', '--help'])",
])
def test_start_up_loads_nothing_heavy(code: str) -> None:
    assert modules_loaded_by(code) == []


def test_a_model_loads_python_control_when_first_needed() -> None:
    code = "import ident.representations as r\nr.random_system(1, 1, 2, 0)"
    assert "control" in modules_loaded_by(code)
