"""Run the examples and inline values of the literate documents, in reading order, one namespace per
document, as the weave runs them (``literate_tools.examples.DocumentRun``).

This imports the parser and the example runner only, not the weave's renderer or site.

Each example and each inline value is its own test item named after the document and the example
(or the line of the value). A failure names its ``file:line`` in the literate source. One failure is
one failure: a later example that reads a name the failed one was to define is skipped, naming the
failure; the examples that do not depend on it still run. Selecting one item (``-k``) runs the
document's earlier items first, as setup.
"""
from __future__ import annotations

import os

import matplotlib
import pytest

from conftest import PROJECT_ROOT
from literate_tools import chunks, examples

matplotlib.use("Agg")

WEB = chunks.read_web(PROJECT_ROOT)
UNITS = [(document, index, unit) for document in WEB.documents
         for index, unit in enumerate(examples.run_order(document))]
RUNS: dict[str, "examples.DocumentRun"] = {}


def unit_id(document: chunks.Document, unit) -> str:
    name = unit.name if isinstance(unit, chunks.Block) else f"value at line {unit.location.line}"
    return f"{os.path.basename(document.path)}::{name}"


@pytest.fixture(scope="module", autouse=True)
def environment():
    """The examples run as the weave runs them: in the project root, with the package importable."""
    with examples.example_environment(PROJECT_ROOT, figures=None):
        yield
    for run in RUNS.values():
        run.runner.close_all()


@pytest.mark.parametrize("document, index, unit", UNITS, ids=[unit_id(d, u) for d, _, u in UNITS])
def test_example(document: chunks.Document, index: int, unit) -> None:
    if document.path not in RUNS:
        RUNS[document.path] = examples.DocumentRun(document, examples.ExampleRunner(PROJECT_ROOT, None))
    outcome = RUNS[document.path].run_until(index)
    title = f"{examples.unit_title(unit)} at {unit.location}"
    if outcome.status == "skipped":
        pytest.skip(f"{title} skipped: {outcome.message}")
    if outcome.status == "failed":
        pytest.fail(f"{title} failed:\n{outcome.message}", pytrace=False)


def test_there_are_examples() -> None:
    assert sum(isinstance(unit, chunks.Block) for _, _, unit in UNITS) >= 3
