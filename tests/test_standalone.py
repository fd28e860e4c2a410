"""A clone needs only the DAISY files beside it: the examples run with nothing else under ../shared.

The reference results moved from ../shared/reference into the repository's reference/ (read through
literate_tools.tangled.examples.reference_path). Here the repository's tracked files are copied into
tmp/project, with tmp/shared/daisy (a link to the real DAISY folder) and nothing else under tmp/shared, and
the examples of every document whose code could read shared or reference data (DATA_READS: five of the sixteen)
run there with this interpreter, ident imported from the copy: about 20 s. The other documents name
neither folder, so they cannot depend on ../shared/reference; running them too would take the whole
examples' time (25 to 80 s here) once more for nothing.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import PROJECT_ROOT, SHARED

# code that could read ../shared or reference/: the helpers, a path through either folder, their names
# as path components, or a DAISY or reference file by name
DATA_READS = re.compile(r"reference_path\(|shared_path\(|\bshared/|\breference/|[\"']shared[\"']|[\"']reference[\"']"
                        r"|msd_uy|\.dat\b")


def code_of(document: Path) -> str:
    return "\n".join(re.findall(r"^```python[^\n]*\n(.*?)^```", document.read_text(), flags=re.M | re.S))


def documents_reading_data() -> list[str]:
    return sorted(path.name for path in (PROJECT_ROOT / "literate").glob("*.md") if DATA_READS.search(code_of(path)))


def test_the_examples_run_without_shared_reference(tmp_path) -> None:
    if not (SHARED / "daisy").is_dir():
        pytest.skip(f"DAISY data not found at {SHARED / 'daisy'}")
    try:
        listed = subprocess.run(["git", "ls-files", "-z"], cwd=PROJECT_ROOT, capture_output=True, check=True)
    except (OSError, subprocess.CalledProcessError) as error:
        pytest.skip(f"not a git checkout ({error})")
    project = tmp_path / "project"
    for name in listed.stdout.decode().split("\0"):
        if name and (PROJECT_ROOT / name).is_file():  # (a file deleted but not yet committed is skipped)
            (project / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(PROJECT_ROOT / name, project / name)
    (tmp_path / "shared").mkdir()
    (tmp_path / "shared" / "daisy").symlink_to((SHARED / "daisy").resolve(), target_is_directory=True)
    assert [p.name for p in (tmp_path / "shared").iterdir()] == ["daisy"]
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join([str(project / "src"), str(project)]),
                   "MPLBACKEND": "Agg"}
    where = subprocess.run([sys.executable, "-c", "import ident; print(ident.__file__)"], cwd=project,
                           env=environment, capture_output=True, text=True, check=True)
    assert Path(where.stdout.strip()).is_relative_to(project / "src")  # the copy's ident, not this one's
    documents = documents_reading_data()
    assert {"03-examples.md", "27-solver.md"} <= set(documents)  # the pattern still finds the readers
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests/test_examples.py",
                          "-k", " or ".join(documents)], cwd=project, env=environment, capture_output=True, text=True)
    summary = run.stdout.strip().splitlines()[-1] if run.stdout.strip() else ""
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-2000:]
    assert re.fullmatch(r"\d+ passed(, \d+ deselected)?(, \d+ warnings?)? in .*", summary), summary

