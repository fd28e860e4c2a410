"""The shape of the package (the house): imports go one way, and functions and modules stay readable.

- No module of ``ident`` imports, directly or through others, a module that imports it back. Every
  ``import`` counts, also one inside a function: a cycle hidden in a function is still a cycle.
  ``from ident.solver import reference`` is an import of the submodule, ``from ident.solver import
  slra`` one of the package.
- A function (or method) has at most 80 lines, its docstring not counted (the docstrings are the
  paper's inline help, with a line per parameter); a module has at most 800 lines.
- Every warning class of the package is exported from ``ident`` (issue 31), so that a user filters
  it by class without knowing the module that raises it.
- The kernel R = [R_0 ... R_ell] is cut into its blocks in ``ident.kernel_layout`` only (issue 28): no
  other module reshapes it by ``ell + 1`` or divides its width by ``ell + 1``.
- No module of ``ident`` imports the literate tools or the examples' helpers they tangle
  (``literate_tools/tangled/examples.py``, issue 28): those serve the repository, not the package.
- One module submits work to executors, ``ident.executors`` (issue 28): one policy for parallel work
  (largest first, results in order, cancelled on Ctrl-C, models across processes as matrices).
- The literate tooling, ``literate_tools/`` (what ``tangle.py`` and ``weave.py`` run), keeps the same
  rules of length and of imports (issue 28); its parser and tangler import the standard library only
  (the tangler runs before anything is installed), the example runner that ``tests/test_examples.py``
  imports reaches neither the renderer nor the site, and the two programs at the root only start it.
- The literate documents are numbered in reading order, 01, 02, ..., without letters, gaps or repeats,
  and none is over 1,500 lines (issue 28): a longer one is two ideas.
- Every random number comes from a seeded generator (``numpy.random.default_rng(seed)``): nothing in
  the package, the chapters, the tests or the benchmarks draws from numpy's global state, directly or
  through python-control's ``rss``/``drss`` (an example built on ``drss`` failed on one machine in CI).
"""
from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "ident"
TOOLS = ROOT / "literate_tools"  # the literate tooling (issue 28): the same rules
PACKAGES = {"ident": PACKAGE, "literate_tools": TOOLS}
MAX_FUNCTION_LINES = 80
MAX_MODULE_LINES = 800


def module_name(path: Path) -> str:
    top = next(name for name, folder in PACKAGES.items() if path.is_relative_to(folder))
    parts = [top, *path.relative_to(PACKAGES[top]).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(path): path for folder in PACKAGES.values() for path in sorted(folder.rglob("*.py"))}
IDENT_MODULES = {name: path for name, path in MODULES.items() if name.split(".")[0] == "ident"}


def imported_names(name: str) -> set[str]:
    """Every module that module `name` imports, anywhere in its code (a name ``from`` a module counts
    as the submodule of that name if there is one, else as the module)."""
    path = MODULES[name]
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # a relative import
                base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1] + ([base] if base else []))
            for alias in node.names:
                submodule = f"{base}.{alias.name}"
                found.add(submodule if submodule in MODULES else base)
    return found


def imports_of(name: str) -> set[str]:
    """The modules of ident (or of literate_tools) that module `name` imports, anywhere in its code."""
    return {module for module in imported_names(name) if module in MODULES and module != name}


GRAPH = {name: imports_of(name) for name in MODULES}


def cycle_through(start: str) -> list[str] | None:
    """A chain of imports from `start` back to itself, or None."""
    stack, seen = [(start, [start])], set()
    while stack:
        name, chain = stack.pop()
        for imported in sorted(GRAPH[name]):
            if imported == start:
                return chain + [start]
            if imported not in seen:
                seen.add(imported)
                stack.append((imported, chain + [imported]))
    return None


def test_the_import_graph_has_no_cycle() -> None:
    cycles = [" -> ".join(chain) for name in MODULES if (chain := cycle_through(name))]
    assert not cycles, cycles


def test_the_solver_imports_nothing_of_the_system_theory() -> None:
    solver = {name for name in MODULES if name == "ident.solver" or name.startswith("ident.solver.")}
    reached, stack = set(), list(solver)
    while stack:
        for imported in GRAPH[stack.pop()]:
            if imported not in reached:
                reached.add(imported)
                stack.append(imported)
    assert reached - solver <= {"ident.structure", "ident.hankel", "ident.kernel_layout", "ident.starts"}, reached - solver


def test_the_kernel_layout_is_the_ground_floor() -> None:
    """``ident.kernel_layout`` (issue 28) imports nothing of ident: the solver and the starts may use it."""
    assert GRAPH["ident.kernel_layout"] == set()


def submitting_modules() -> set[str]:
    """The modules of ident with a call of some object's ``submit`` method."""
    return {name for name, path in MODULES.items() if name.startswith("ident")
            for node in ast.walk(ast.parse(path.read_text()))
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "submit"}


def test_exactly_one_module_submits_work_to_executors() -> None:
    assert submitting_modules() == {"ident.executors"}


def function_lengths(path: Path) -> list[tuple[int, str]]:
    """(lines without the docstring, name:line) of every function and method of a module."""
    lengths = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            lines = node.end_lineno - node.lineno + 1
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(getattr(body[0], "value", None), ast.Constant) \
                    and isinstance(body[0].value.value, str):
                lines -= body[0].end_lineno - body[0].lineno + 1
            lengths.append((lines, f"{node.name}:{node.lineno}"))
    return lengths


@pytest.mark.parametrize("name", sorted(MODULES))
def test_functions_and_modules_stay_short(name: str) -> None:
    path = MODULES[name]
    n_lines = len(path.read_text(encoding="utf-8").splitlines())
    assert n_lines <= MAX_MODULE_LINES, f"{path.name} has {n_lines} lines"
    long = [(lines, where) for lines, where in function_lengths(path) if lines > MAX_FUNCTION_LINES]
    assert not long, f"{path.name}: functions over {MAX_FUNCTION_LINES} lines: {long}"


# --- issue 31 point 7 (the small edges): the warning classes are exported ---------------------------------

def warning_classes() -> dict[str, str]:
    """Each class of the package whose base is a warning class, with the module that defines it."""
    found = {}
    for name, path in IDENT_MODULES.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef) and any(ast.unparse(base).endswith("Warning") for base in node.bases):
                found[node.name] = name
    return found


def test_every_warning_class_is_exported() -> None:
    import importlib

    import ident

    classes = warning_classes()
    assert {"UnstableModelWarning", "IllConditionedWarning", "SLRAWarning", "MisfitWarning"} <= set(classes)
    for name, module in classes.items():
        assert name in ident.__all__, f"{name} (from {module}) is not in ident.__all__"
        assert getattr(ident, name) is getattr(importlib.import_module(module), name), name


# --- issue 28 point 6: the literate tooling is a package of the house -------------------------------------

def reached_from(name: str) -> set[str]:
    """The modules of the project that module `name` imports, directly or through others."""
    reached, stack = set(), [name]
    while stack:
        for imported in GRAPH[stack.pop()]:
            if imported not in reached:
                reached.add(imported)
                stack.append(imported)
    return reached


def test_the_tooling_is_checked_as_the_package_is() -> None:
    tools = {name for name in MODULES if name.split(".")[0] == "literate_tools"}
    assert {"literate_tools.chunks", "literate_tools.tangle", "literate_tools.examples", "literate_tools.render",
            "literate_tools.site"} <= tools, tools
    assert (TOOLS / "site.css").is_file()  # the page style, read when weaving


@pytest.mark.parametrize("name", ["literate_tools.chunks", "literate_tools.tangle"])
def test_the_tangler_needs_only_the_standard_library(name: str) -> None:
    outside = {module for module in imported_names(name)
               if module.split(".")[0] not in sys.stdlib_module_names and module.split(".")[0] != "literate_tools"}
    assert not outside, f"{name} imports {sorted(outside)}: tangle.py must run before anything is installed"
    assert reached_from(name) <= {"literate_tools.chunks"}, reached_from(name)


def test_the_example_runner_needs_neither_the_renderer_nor_the_site() -> None:
    reached = reached_from("literate_tools.examples")
    assert reached <= {"literate_tools.chunks", "literate_tools.xref"}, reached
    test_module = ast.parse((ROOT / "tests" / "test_examples.py").read_text(encoding="utf-8"))
    imported = {alias.name if isinstance(node, ast.Import) else f"{node.module}.{alias.name}"
                for node in ast.walk(test_module) if isinstance(node, (ast.Import, ast.ImportFrom))
                for alias in node.names}
    ours = {module for module in imported if module.split(".")[0] in ("literate_tools", "weave", "tangle")}
    assert ours == {"literate_tools.chunks", "literate_tools.examples"}, ours


@pytest.mark.parametrize("program", ["tangle.py", "weave.py"])
def test_the_programs_at_the_root_only_start_the_tooling(program: str) -> None:
    tree = ast.parse((ROOT / program).read_text(encoding="utf-8"))
    defined = [node.name for node in ast.walk(tree) if isinstance(node, (ast.FunctionDef, ast.ClassDef))]
    assert not defined, f"{program} defines {defined}: the code belongs in literate_tools/"
    assert len((ROOT / program).read_text(encoding="utf-8").splitlines()) <= 40, program


GLOBAL_RANDOM_STATE = re.compile(r"\b(?:control\.)?d?rss\(|\b(?:np|numpy)\.random\.(?!default_rng\b|Generator\b|SeedSequence\b)\w+")


@pytest.mark.parametrize("folder", ["src", "literate", "tests", "benchmarks", "literate_tools"])
def test_random_numbers_come_from_seeded_generators(folder: str) -> None:
    this_file = Path(__file__).resolve()
    hits = [f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
            for path in sorted((ROOT / folder).rglob("*")) if path.suffix in {".py", ".md"} and path != this_file
            for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
            if GLOBAL_RANDOM_STATE.search(line)]
    assert not hits, "draws from numpy's global random state:\n" + "\n".join(hits)


# --- issue 28 points 1 and 3: ident's front door stays small; one table names the starts -------------------

MAX_FRONT_DOOR_LINES = 400


def test_the_front_door_of_ident_is_at_most_400_lines() -> None:
    n_lines = len((PACKAGE / "identification.py").read_text(encoding="utf-8").splitlines())
    assert n_lines <= MAX_FRONT_DOOR_LINES, f"identification.py has {n_lines} lines"


def start_names() -> list[str]:
    """The keys of the table of starts, read from ident/starts.py's source (the dict assigned to STARTS)."""
    tree = ast.parse((PACKAGE / "starts.py").read_text(encoding="utf-8"))
    table = next(node.value for node in ast.walk(tree) if isinstance(node, ast.Assign)
                 and any(isinstance(target, ast.Name) and target.id == "STARTS" for target in node.targets))
    assert isinstance(table, ast.Dict), "STARTS must be a dict display: the table of named starts"
    return [key.value for key in table.keys]


def code_strings(path: Path) -> list[str]:
    """The string constants of a module's code: docstrings, the text of f-strings and the names listed in
    ``__all__`` (the module's functions) left out."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
                  and node.body and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)}
    in_fstrings = {id(part) for node in ast.walk(tree) if isinstance(node, ast.JoinedStr) for part in node.values}
    exports = {id(constant) for node in tree.body if isinstance(node, ast.Assign)
               and any(isinstance(target, ast.Name) and target.id == "__all__" for target in node.targets)
               for constant in ast.walk(node.value)}
    left_out = docstrings | in_fstrings | exports
    return [node.value for node in ast.walk(tree) if isinstance(node, ast.Constant) and isinstance(node.value, str)
            and id(node) not in left_out]


def test_start_names_appear_in_one_table_only() -> None:
    names = start_names()
    assert len(names) >= 3 and len(set(names)) == len(names), names
    found = {(module, name): code_strings(path).count(name) for module, path in IDENT_MODULES.items() for name in names}
    elsewhere = {key: count for key, count in found.items() if count and key[0] != "ident.starts"}
    assert not elsewhere, f"start names written outside the table of ident.starts: {elsewhere}"
    assert all(found["ident.starts", name] == 1 for name in names), {name: found["ident.starts", name] for name in names}


MAX_CHAPTER_LINES = 1500
CHAPTERS = sorted((ROOT / "literate").glob("*.md"))


def test_the_chapters_are_numbered_in_reading_order_without_letters() -> None:
    numbers = [path.name.split("-", 1)[0] for path in CHAPTERS]
    assert numbers == [f"{k:02d}" for k in range(1, len(CHAPTERS) + 1)], [path.name for path in CHAPTERS]


@pytest.mark.parametrize("chapter", [path.name for path in CHAPTERS])
def test_no_chapter_is_over_1500_lines(chapter: str) -> None:
    n_lines = len((ROOT / "literate" / chapter).read_text(encoding="utf-8").splitlines())
    assert n_lines <= MAX_CHAPTER_LINES, f"{chapter} has {n_lines} lines"


def cuts_a_kernel_into_blocks(node: ast.AST) -> bool:
    """A ``reshape`` with ``ell + 1`` among its arguments, or a width divided by ``(ell + 1)``: R cut into
    its blocks R_0, ..., R_ell by hand."""
    def is_ell_plus_one(sub: ast.AST) -> bool:
        return (isinstance(sub, ast.BinOp) and isinstance(sub.op, ast.Add) and isinstance(sub.left, ast.Name)
                and sub.left.id == "ell" and isinstance(sub.right, ast.Constant) and sub.right.value == 1)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "reshape":
        return any(is_ell_plus_one(sub) for arg in node.args for sub in ast.walk(arg))
    return isinstance(node, ast.BinOp) and isinstance(node.op, ast.FloorDiv) and is_ell_plus_one(node.right)


def test_the_kernel_is_cut_into_its_blocks_in_kernel_layout_only() -> None:
    """The layout of R = [R_0 ... R_ell] has one home (issue 28): kernel_layout.kernel_blocks and
    blocks_kernel (split_kernel and join_kernel with the split of each block into Q_i and -P_i)."""
    found = {f"{name}:{node.lineno}" for name, path in IDENT_MODULES.items() if name != "ident.kernel_layout"
             for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))) if cuts_a_kernel_into_blocks(node)}
    assert not found, found


def test_the_package_imports_nothing_of_the_repository_tooling() -> None:
    """The examples' helpers (``literate_tools/tangled/examples.py``, tangled from 03-examples.md) and the
    literate tools serve the repository's examples, tests and benchmarks, not the package (issue 28): no
    module of ident imports them, and none is left in the package."""
    found = {name: sorted(module for module in imported_names(name)
                          if module.split(".")[0] == "literate_tools" or module == "ident.examples")
             for name in IDENT_MODULES}
    assert not any(found.values()), {name: modules for name, modules in found.items() if modules}
    assert not (PACKAGE / "examples.py").exists()
