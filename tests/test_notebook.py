"""Each literate document opens as a notebook through jupytext, and exactly its examples are code
cells (tests/test_examples.py runs them, in order, once)."""
from __future__ import annotations

import jupytext
import pytest

import tangle
from conftest import PROJECT_ROOT

DOCUMENTS = tangle.literate_files(PROJECT_ROOT)


@pytest.mark.parametrize("path", DOCUMENTS, ids=[p.name for p in DOCUMENTS])
def test_document_is_a_notebook_whose_code_cells_are_the_examples(path) -> None:
    notebook = jupytext.read(path)
    code_cells = [cell.source for cell in notebook.cells if cell.cell_type == "code"]
    document = tangle.parse_document(path.read_text(encoding="utf-8"), path.name)
    examples = ["\n".join(["# example: " + b.name] + b.lines) for b in document.items
                if isinstance(b, tangle.Block) and b.kind == "example"]
    assert code_cells == examples  # so the notebook runs what tests/test_examples.py runs


def test_ipynb_conversion_roundtrip(tmp_path) -> None:
    """The file written by `jupytext --to ipynb` reads back with the same code cells."""
    source = PROJECT_ROOT / "literate" / "08-structure.md"
    target = tmp_path / "structure.ipynb"
    jupytext.write(jupytext.read(source), target, fmt="ipynb")
    cells = jupytext.read(target).cells
    assert sum(cell.cell_type == "code" for cell in cells) >= 2
