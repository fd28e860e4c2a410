"""The example runner: the examples and inline values of a document, run in reading order in one
namespace, with what they print and draw.

This is what ``tests/test_examples.py`` imports to run the examples as tests, as the weave runs
them (``DocumentRun``, ``ExampleRunner``, ``example_environment``, ``run_order``, ``unit_title``);
it needs neither the renderer nor the site.  One failure is one failure: a later example or inline
value that reads a name a failed one was to define is skipped, naming the failure; the others run.
Figures are kept (as PNG files without metadata) only when the runner is given an output folder.
"""
from __future__ import annotations

import ast
import builtins
import contextlib
import dataclasses
import io
import os
import re
import struct
import symtable
import sys
import tempfile
import traceback
import warnings
from pathlib import Path

from literate_tools import chunks
from literate_tools.xref import slug


FIGURE_DPI = 110


# --------------------------------------------------------------------------------------------
# Running the examples


@dataclasses.dataclass
class Figure:
    path: str  # relative to the output folder, with forward slashes
    width: int | None
    height: int | None


@dataclasses.dataclass
class Result:
    """What an example printed and drew."""

    stdout: str = ""
    stderr: str = ""
    figures: list[Figure] = dataclasses.field(default_factory=list)


def png_size(data: bytes) -> tuple[int | None, int | None]:
    if data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR":
        width, height = struct.unpack(">II", data[16:24])
        return width, height
    return None, None


def strip_png_metadata(data: bytes) -> bytes:
    """The PNG without its text and time chunks (so that the same figure gives the same bytes)."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        return data
    out, position = [data[:8]], 8
    while position + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[position:position + 8])
        end = position + 12 + length
        if kind not in (b"tEXt", b"zTXt", b"iTXt", b"tIME"):
            out.append(data[position:end])
        position = end
    return b"".join(out)


def compact_png(data: bytes) -> bytes:
    """A smaller PNG of the same picture: an opaque figure as 256 colours (Pillow), no metadata.

    Plots have few colours besides the anti-aliasing shades, so the palette image looks the same at
    a third of the size; a figure with transparent pixels is only stripped of its metadata.
    """
    data = strip_png_metadata(data)
    try:
        from PIL import Image
    except ImportError:  # Pillow comes with matplotlib; without it the figure stays as it is
        return data
    try:
        with Image.open(io.BytesIO(data)) as image:
            image.load()
            if image.mode in ("RGBA", "LA", "PA") and image.getchannel("A").getextrema()[0] < 255:
                return data
            if image.mode == "P":
                return data
            palette = image.convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT,
                                                    dither=Image.Dither.NONE)
            buffer = io.BytesIO()
            palette.save(buffer, format="PNG", optimize=True)
    except Exception:  # not a picture Pillow can read: leave it alone
        return data
    smaller = strip_png_metadata(buffer.getvalue())
    return smaller if len(smaller) < len(data) else data


def folder_state(folder: Path) -> dict[str, tuple[int, int]]:
    if not folder.is_dir():
        return {}
    return {p.relative_to(folder).as_posix(): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in folder.rglob("*") if p.is_file()}


# a folder made by tempfile (mkdtemp, TemporaryDirectory): a random name in the temporary folder
TEMPORARY_NAME = re.compile("(" + re.escape(tempfile.gettempdir().rstrip(os.sep) + os.sep) + r")tmp[a-z0-9_]{8}\b")


class ExampleFailure(Exception):
    """An example or an inline value raised; the message is its traceback (and what it printed)."""

    def __init__(self, message: str, line: int | None = None):
        super().__init__(message)
        self.line = line  # the line of the document whose top-level statement raised, if known


def failing_line(error: BaseException, filename: str) -> int | None:
    """The line of the top-level statement of ``filename`` that was running when ``error`` was raised."""
    line, trace = None, error.__traceback__
    while trace is not None:
        code = trace.tb_frame.f_code
        if code.co_filename == filename and code.co_name == "<module>":
            line = trace.tb_lineno
        trace = trace.tb_next
    return line


class ExampleRunner:
    """Runs examples and collects their output and figures (figures only when ``out`` is given)."""

    def __init__(self, root: Path, out: Path | None):
        self.root = root
        self.out = out
        self.figures = out / "figures" if out is not None else None
        self.seen_figures: list = []  # matplotlib figures already shown (kept alive: ids stay unique)

    def run(self, block: chunks.Block, namespace: dict, base: str) -> Result:
        source = "\n" * (block.body_location.line - 1) + "\n".join(block.lines) + "\n"
        code = compile(source, str(self.root / block.location.file), "exec")
        before = folder_state(self.figures) if self.figures else {}
        stdout, stderr = io.StringIO(), io.StringIO()
        try:
            with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
                exec(code, namespace)
        except (Exception, SystemExit) as error:
            trace = "".join(traceback.format_exception(type(error), error, error.__traceback__.tb_next))
            printed = stdout.getvalue() + stderr.getvalue()
            if printed:
                trace = "output before the failure:\n" + printed.rstrip("\n") + "\n" + trace
            raise ExampleFailure(trace.rstrip(), failing_line(error, code.co_filename)) from None
        result = Result(self.clean(stdout.getvalue()), self.clean(stderr.getvalue()))
        if self.figures is None:
            self.new_figures(namespace)  # closed, not kept
            return result
        after = folder_state(self.figures)
        written = sorted(name for name, state in after.items() if before.get(name) != state)
        for name in written:
            path = self.figures / name
            data = path.read_bytes()
            if path.suffix.lower() == ".png":
                compact = compact_png(data)
                if compact != data:
                    path.write_bytes(compact)
                data = compact
            result.figures.append(Figure("figures/" + name, *png_size(data)))
        for k, figure in enumerate(self.new_figures(namespace), start=1):
            if written:  # the example chose what to show by writing files
                continue
            name = f"{base}-{k}.png" if k > 1 else f"{base}.png"
            result.figures.append(self.save(figure, name))
        return result

    def evaluate(self, value: chunks.InlineValue, namespace: dict, alone: bool) -> str:
        """The text of an inline value: ``str`` of the expression's value, Markdown; several lines
        (a table, a list) only for a value that stands alone on its line."""
        source = "\n" * (value.location.line - 1) + value.expression
        try:
            code = compile(source, str(self.root / value.location.file), "eval")
            text = str(eval(code, namespace)).strip("\n")
        except Exception as error:
            trace = "".join(traceback.format_exception(type(error), error, error.__traceback__.tb_next))
            raise ExampleFailure(trace.rstrip()) from None
        if "\n" in text and not alone:
            raise ExampleFailure(f"its value has several lines ({text[:60]!r}...); a value of several lines "
                                 "(a table, a list) must stand alone on its line of the text")
        if "`{python}" in text:
            raise ExampleFailure("its value holds an inline value itself")
        return text

    def clean(self, text: str) -> str:
        """Printed output with the paths that change from run to run made the same.

        The output folder reads ``docs``, the project root ``.`` and the shared folder beside it
        ``../shared``, wherever they are; a temporary folder of ``tempfile`` reads ``tmpXXXXXXXX``.
        """
        shared = self.root.parent / "shared"  # the project's data folder beside it
        for folder, prefix, name in ((self.out, "docs/", "docs"), (shared, "../shared/", "../shared"),
                                     (self.root, "", ".")):
            text = text.replace(str(folder) + os.sep, prefix).replace(str(folder), name)
        return TEMPORARY_NAME.sub(r"\g<1>tmpXXXXXXXX", text)

    def new_figures(self, namespace: dict) -> list:
        """Figures left open in pyplot, then Figure objects newly bound to top-level names."""
        if "matplotlib" not in sys.modules:
            return []
        from matplotlib.figure import Figure as MatplotlibFigure

        found = []
        if "matplotlib.pyplot" in sys.modules:
            import matplotlib.pyplot as plt

            for number in plt.get_fignums():
                figure = plt.figure(number)
                found.append(figure)
                plt.close(figure)
        seen = {id(f) for f in self.seen_figures}
        for value in namespace.values():
            if isinstance(value, MatplotlibFigure) and id(value) not in seen and value not in found:
                found.append(value)
        self.seen_figures.extend(found)
        return found

    def save(self, figure, name: str) -> Figure:
        self.figures.mkdir(parents=True, exist_ok=True)
        buffer = io.BytesIO()
        figure.savefig(buffer, format="png", dpi=FIGURE_DPI, metadata={"Software": None})
        data = compact_png(buffer.getvalue())
        (self.figures / name).write_bytes(data)
        return Figure("figures/" + name, *png_size(data))

    def close_all(self) -> None:
        if "matplotlib.pyplot" in sys.modules:
            sys.modules["matplotlib.pyplot"].close("all")
        self.seen_figures.clear()


# --------------------------------------------------------------------------------------------
# A document read from top to bottom: its examples and inline values in one namespace


BUILTIN_NAMES = frozenset(dir(builtins))


def module_names(source: str, mode: str = "exec", after: int = 0) -> tuple[set[str], set[str]]:
    """Names a piece of code binds in the module namespace, and names it reads there before binding
    them (its inputs).  Static, statement by statement, so a failed example's names are known even
    though it never bound them; ``after``: only the bindings of the top-level statements that end on
    or after that line of ``source`` (those a failure at that line left undone)."""
    tree = ast.parse(source, mode=mode)
    bound: set[str] = set()
    needed: set[str] = set()
    if mode == "eval":
        names_of(ast.Expression(tree.body), bound, needed)
    undone: set[str] = set()
    for statement in getattr(tree, "body", []) if mode == "exec" else []:
        statement_names(statement, bound, needed)
        if after and statement.end_lineno >= after:
            undone |= module_names(ast.unparse(statement))[0]
    return (undone if after else bound), needed - BUILTIN_NAMES


def statement_names(statement: ast.stmt, bound: set[str], needed: set[str]) -> None:
    """Add a statement's module-level bindings and its reads of names not bound before them."""
    if isinstance(statement, (ast.For, ast.AsyncFor)):
        names_of(ast.Expression(statement.iter), bound, needed)
        names_of(ast.Assign([statement.target], ast.Constant(None), lineno=0), bound, needed)
        parts = [statement.body, statement.orelse]
    elif isinstance(statement, (ast.With, ast.AsyncWith)):
        for item in statement.items:
            names_of(ast.Expression(item.context_expr), bound, needed)
            if item.optional_vars is not None:
                names_of(ast.Assign([item.optional_vars], ast.Constant(None), lineno=0), bound, needed)
        parts = [statement.body]
    elif isinstance(statement, (ast.If, ast.While)):
        names_of(ast.Expression(statement.test), bound, needed)
        parts = [statement.body, statement.orelse]
    elif isinstance(statement, ast.Try):
        for handler in statement.handlers:
            if handler.type is not None:
                names_of(ast.Expression(handler.type), bound, needed)
        parts = [statement.body, *(h.body for h in statement.handlers), statement.orelse, statement.finalbody]
        bound.update(h.name for h in statement.handlers if h.name)
    else:
        names_of(statement, bound, needed)
        return
    for part in parts:
        for inner in part:
            statement_names(inner, bound, needed)


def names_of(node: ast.AST, bound: set[str], needed: set[str]) -> None:
    expression = isinstance(node, ast.Expression)
    source = ast.unparse(ast.fix_missing_locations(node.body if expression else node))
    table = symtable.symtable(source, "<example>", "eval" if expression else "exec")
    reads, binds = global_names(table, top=True)
    needed |= reads - bound
    bound |= binds


def global_names(table: symtable.SymbolTable, top: bool) -> tuple[set[str], set[str]]:
    """(read, bound) module-level names of a symbol table and the tables nested in it."""
    reads, binds = set(), set()
    for symbol in table.get_symbols():
        name = symbol.get_name()
        in_module = top or symbol.is_global()
        if in_module and symbol.is_referenced():
            reads.add(name)
        if in_module and (symbol.is_assigned() or symbol.is_imported()) and (top or symbol.is_declared_global()):
            binds.add(name)
    for child in table.get_children():
        child_reads, child_binds = global_names(child, top=False)
        reads |= child_reads
        binds |= child_binds
    return reads, binds


@dataclasses.dataclass
class Outcome:
    """What became of an example or an inline value."""

    status: str  # "ok", "failed" or "skipped"
    message: str = ""  # the traceback of a failure, the reason of a skip
    result: Result | None = None  # an example's output and figures
    value: str | None = None  # an inline value's text

    @property
    def ok(self) -> bool:
        return self.status == "ok"


def run_order(document: chunks.Document) -> list:
    """The examples and inline values of a document in the order they run: reading order, except
    that an inline value that reads a name no example above it binds runs right after the example
    below it that binds the last such name (the text may state a result before the example that
    computes it)."""
    units = document.runnable()
    binds = [module_names("\n".join(u.lines))[0] if isinstance(u, chunks.Block) else set() for u in units]
    order, waiting, seen = [], [], set()  # waiting: [value, the names it still waits for]
    for k, unit in enumerate(units):
        if isinstance(unit, chunks.InlineValue):
            try:
                needed = module_names(unit.expression, "eval")[1]
            except SyntaxError:
                needed = set()  # evaluating it reports the error
            missing = (needed - seen) & set().union(*binds[k:])
            if missing:
                waiting.append([unit, missing])
            else:
                order.append(unit)
            continue
        order.append(unit)
        seen |= binds[k]
        for entry in waiting:
            entry[1] -= binds[k]
        order += [value for value, missing in waiting if not missing]
        waiting = [entry for entry in waiting if entry[1]]
    return order + [value for value, _ in waiting]


def unit_title(unit) -> str:
    if isinstance(unit, chunks.Block):
        return f"example '{unit.name}'"
    return f"inline value `{{python}} {unit.expression}`"


class DocumentRun:
    """Runs a document's examples and inline values in reading order, in one namespace.

    One failure is one failure: a later unit that reads a name the failed one binds (directly, or
    through a unit skipped for that reason) is skipped, naming the failure; the others still run.
    """

    def __init__(self, document: chunks.Document, runner: ExampleRunner, anchors: dict | None = None):
        self.document = document
        self.runner = runner
        self.anchors = anchors or {}
        self.namespace: dict = {"__name__": f"example:{document.path}"}
        self.units = run_order(document)
        self.lines = dict(document.text_lines())
        self.outcomes: list[Outcome] = []
        self.unavailable: dict[str, str] = {}  # name -> the failed unit that was to bind it

    def run_until(self, index: int) -> Outcome:
        """The outcome of unit ``index``, running the units before it first if they have not run."""
        while len(self.outcomes) <= index:
            self.outcomes.append(self.run_next(self.units[len(self.outcomes)]))
        return self.outcomes[index]

    def run_all(self) -> list[Outcome]:
        if self.units:
            self.run_until(len(self.units) - 1)
        self.runner.close_all()
        return self.outcomes

    def run_next(self, unit) -> Outcome:
        example = isinstance(unit, chunks.Block)
        source = "\n".join(unit.lines) if example else unit.expression
        try:
            bound, needed = module_names(source, "exec" if example else "eval")
        except SyntaxError:
            bound, needed = set(), set()  # compiling it reports the error with its line
        missing = sorted(needed & self.unavailable.keys())
        if missing:
            causes = sorted({self.unavailable[name] for name in missing})
            outcome = Outcome("skipped", f"it reads {', '.join(missing)}, which {' and '.join(causes)} "
                                         "did not define")
        else:
            try:
                if example:
                    base = Path(self.document.path).stem + "-" + self.anchor(unit)
                    outcome = Outcome("ok", result=self.runner.run(unit, self.namespace, base))
                else:
                    line = self.lines[unit.location.line]
                    alone = line.strip() == line[unit.start:unit.end]
                    outcome = Outcome("ok", value=self.runner.evaluate(unit, self.namespace, alone))
            except ExampleFailure as failure:
                outcome = Outcome("failed", str(failure))
                if example and failure.line is not None:  # what ran before the failing statement stands
                    bound = module_names(source, after=failure.line - unit.body_location.line + 1)[0]
        if not outcome.ok:
            cause = f"{unit_title(unit)} ({unit.location})"
            if outcome.status == "skipped":
                root = self.unavailable[missing[0]]
                cause += f", skipped because of {root.split(', skipped because of ')[-1]},"
            self.unavailable.update((name, cause) for name in bound)
        return outcome

    def anchor(self, block: chunks.Block) -> str:
        return self.anchors.get(block.location, "example-" + slug(block.name)).removeprefix("example-")

    def problems(self) -> list[str]:
        """One message per unit that failed or was skipped, with its file:line."""
        return [f"{unit.location}: {unit_title(unit)} {outcome.status}"
                + (f":\n{outcome.message}" if outcome.status == "failed" else f": {outcome.message}")
                for unit, outcome in zip(self.units, self.outcomes) if not outcome.ok]


@contextlib.contextmanager
def example_environment(root: Path, figures: Path | None):
    """Working directory, import path, IDENT_FIGURES (if given) and a non-interactive matplotlib for
    the examples."""
    saved_cwd, saved_path = os.getcwd(), list(sys.path)
    saved_env = {k: os.environ.get(k) for k in ("IDENT_FIGURES", "MPLBACKEND", "SOURCE_DATE_EPOCH")}
    if figures is not None:
        os.environ["IDENT_FIGURES"] = str(figures)
    else:
        os.environ.pop("IDENT_FIGURES", None)
    os.environ["MPLBACKEND"] = "Agg"
    os.environ["SOURCE_DATE_EPOCH"] = "0"  # no dates in PDF/PS figures an example might write
    if (root / "src").is_dir():
        sys.path.insert(0, str(root / "src"))
    saved_rc = None
    try:
        import matplotlib

        matplotlib.use("Agg")
        saved_rc = matplotlib.rcParams.copy()
        matplotlib.rcParams["svg.hashsalt"] = "ident-weave"
        matplotlib.rcParams["figure.max_open_warning"] = 0
    except ImportError:
        pass
    os.chdir(root)
    try:
        with warnings.catch_warnings():
            yield
    finally:
        os.chdir(saved_cwd)
        sys.path[:] = saved_path
        for key, value in saved_env.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
        if saved_rc is not None:
            import matplotlib

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                matplotlib.rcParams.update(saved_rc)
