"""The documents of the literate program as a whole: the introduction's list of them is complete and
in reading order."""
from __future__ import annotations

import re

import pytest

import tangle
from conftest import PROJECT_ROOT


def listed_documents(text: str, names: list[str]) -> list[str]:
    """The documents the list of "## The documents" names, a range "A to B" expanded."""
    section = text.split("## The documents", 1)[1].split("\n## ", 1)[0]
    listed = []
    for item in re.split(r"\n\d+\. ", "\n" + section)[1:]:
        mentioned = re.findall(r"`(\d\d[\w-]*\.md)`", item)
        if len(mentioned) == 2 and " to " in item:
            first, last = names.index(mentioned[0]), names.index(mentioned[1])
            listed += names[first:last + 1]
        else:
            listed += mentioned[:1]
    return listed


def test_the_introduction_lists_every_document_in_reading_order() -> None:
    names = [path.name for path in tangle.literate_files(PROJECT_ROOT)]
    text = (PROJECT_ROOT / "literate" / "01-introduction.md").read_text(encoding="utf-8")
    assert listed_documents(text, names) == names


def test_the_main_job_installs_what_the_examples_import() -> None:
    # the main job installs `.[docs]` only and the weave runs every example: a module an example
    # imports must be a dependency or in the docs extra (pandas was missing once: the weave failed)
    import ast
    import sys

    tomllib = pytest.importorskip("tomllib")
    project = tomllib.loads((PROJECT_ROOT / "pyproject.toml").read_text())["project"]
    installed = {re.split(r"[\[<>=;! ]", requirement, maxsplit=1)[0].lower()
                 for requirement in project["dependencies"] + project["optional-dependencies"]["docs"]}
    imported = {}
    for document in tangle.read_web(PROJECT_ROOT).documents:
        for block in document.items:
            if isinstance(block, tangle.Block) and block.kind == "example":
                for node in ast.walk(ast.parse("\n".join(block.lines))):
                    names = ([alias.name for alias in node.names] if isinstance(node, ast.Import) else
                             [node.module] if isinstance(node, ast.ImportFrom) and node.module and not node.level
                             else [])
                    for name in names:
                        imported.setdefault(name.split(".")[0], document.path)
    missing = {name: path for name, path in imported.items()
               if name not in sys.stdlib_module_names and name not in ("ident", "literate_tools")  # the repository's own
               and name.lower() not in installed}
    assert not missing, f"examples import modules the main job does not install: {missing}"
