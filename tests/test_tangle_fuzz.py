"""Fuzzing the tangler: random mutations of the real literate documents either tangle or raise
TangleError (with file:line), never another exception."""
from __future__ import annotations

import random
import re

import pytest

import tangle
from conftest import PROJECT_ROOT

FRAGMENTS = ["```", "```python", "```python .noeval", "~~~", "# <<", "# <<x>>=", "# <<x>>+=", "<<x>>",
             "<<src/ident/hankel.py>>", "# example: e", "    <<", "<<>>", "# <<src/ident/new.py>>=", "\r",
             "  ```python", "````", "# << a >>=", "<<a -> b>>", "\t<<x>>", ""]


def mutate(lines: list[str], rng: random.Random) -> list[str]:
    lines = list(lines)
    for _ in range(rng.randint(1, 4)):
        if not lines:
            lines.append(rng.choice(FRAGMENTS))
            continue
        i = rng.randrange(len(lines))
        action = rng.randrange(6)
        if action == 0:
            del lines[i]
        elif action == 1:
            lines.insert(i, rng.choice(FRAGMENTS))
        elif action == 2:
            lines.insert(i, lines[rng.randrange(len(lines))])
        elif action == 3:
            j = rng.randrange(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
        elif action == 4:
            lines[i] = lines[i][: rng.randrange(len(lines[i]) + 1)]
        else:
            del lines[i: i + rng.randint(1, 30)]
    return lines


DOCUMENTS = {path.name: path.read_text(encoding="utf-8").split("\n") for path in tangle.literate_files(PROJECT_ROOT)}


@pytest.mark.parametrize("seed", range(40))
def test_mutated_documents_tangle_or_raise_tangle_error(tmp_path, seed) -> None:
    rng = random.Random(seed)
    for name, lines in DOCUMENTS.items():
        target = tmp_path / "literate" / name
        target.parent.mkdir(parents=True, exist_ok=True)
        mutated = mutate(lines, rng) if rng.random() < 0.5 else lines
        target.write_text("\n".join(mutated), encoding="utf-8")
    try:
        outputs, _ = tangle.tangle(tmp_path)
    except tangle.TangleError as error:
        first = str(error).splitlines()[0]
        assert re.match(r"^(literate/[^:]+\.md:\d+: |--where|src/)", first), first
    else:
        assert all(name.startswith("src/ident/") for name in outputs)
