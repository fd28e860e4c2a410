"""The documents of the literate program as a whole: the introduction's list of them is complete and
in reading order."""
from __future__ import annotations

import re

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
