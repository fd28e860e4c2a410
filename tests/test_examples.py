"""Run the example blocks of the literate documents, in reading order, one namespace per document.

Each example is its own test item named after the document and the example; a failure names the
example and its ``file:line`` in the literate source.
"""
from __future__ import annotations

import os
import traceback

import matplotlib
import pytest

import tangle
from conftest import PROJECT_ROOT

matplotlib.use("Agg")

WEB = tangle.read_web(PROJECT_ROOT)
EXAMPLES = [(doc.path, block) for doc in WEB.documents for block in doc.items
            if isinstance(block, tangle.Block) and block.kind == "example"]
NAMESPACES: dict[str, dict] = {}
FAILED: dict[str, str] = {}


def run_example(block: tangle.Block, namespace: dict) -> None:
    """Execute an example so that tracebacks point at the literate file and line."""
    source = "\n" * (block.body_location.line - 1) + "\n".join(block.lines) + "\n"
    code = compile(source, str(PROJECT_ROOT / block.location.file), "exec")
    exec(code, namespace)


@pytest.mark.parametrize("document, block", EXAMPLES,
                         ids=[f"{os.path.basename(d)}::{b.name}" for d, b in EXAMPLES])
def test_example(document: str, block: tangle.Block) -> None:
    if document in FAILED:
        pytest.fail(f"an earlier example of {document} failed: {FAILED[document]}")
    namespace = NAMESPACES.setdefault(document, {"__name__": f"example:{document}"})
    try:
        run_example(block, namespace)
    except Exception:
        FAILED[document] = f"'{block.name}' at {block.location}"
        pytest.fail(f"example '{block.name}' at {block.location} failed:\n{traceback.format_exc()}")


def test_there_are_examples() -> None:
    assert len(EXAMPLES) >= 3
