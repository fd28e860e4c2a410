#!/usr/bin/env python3
"""Weave the literate sources of ident (``literate/*.md``) into a browsable document in ``docs/``.

``python weave.py`` writes, from the documents that ``tangle.py``
reads:

* one HTML page per literate document and ``index.html`` with the contents, an index of the
  chunks and an index of the package's public names (``ident.__all__``);
* ``style.css``: the page style and the Pygments highlighting classes;
* ``figures/``: the figures of the examples, as PNG files without metadata;
* ``notebooks/``: each document as an executed Jupyter notebook (jupytext; outputs filled in from
  the same run as the pages, no kernel needed).

Mathematics is converted from LaTeX to MathML when weaving (latex2mathml), so the pages need
neither JavaScript nor a network connection.  The example blocks run in reading order, one
namespace per document, as ``tests/test_examples.py`` runs them: with the project root as the
working directory and ``IDENT_FIGURES`` naming ``docs/figures``.  Under each example the page shows
what it printed and its figures: files the example wrote into ``$IDENT_FIGURES``; or, if it wrote
none, the matplotlib figures it left open in pyplot and the ``matplotlib.figure.Figure`` objects it
bound to new top-level names.  An *inline value* ```{python} expression``` in the text is replaced
by the expression's value at that place of the document (after the examples above it ran; or after
the example below that defines a name it reads), inside a span whose title shows the expression; a
value of several lines that stands alone on its line is rendered as Markdown of its own (a table).

The pages have the apparatus of a paper (the syntax is in README.md, "The woven document"): parts,
display formulas, figures and captioned tables numbered through all documents and referred to by
label (``@eq:NAME``, ``@fig:NAME``, ``@tbl:NAME``), citations ``[@KEY]`` of a numbered
bibliography, and mentions of a document's file name as links reading its title.  The pages are
parsed and numbered first, every one of them, and rendered second, so that a reference may point
forward or to another page.

The weave is all or nothing.  It writes into a new folder beside the output folder and moves the
files into the output folder only when every example and inline value ran; files whose bytes did not
change are not touched.  Otherwise it exits with status 1, naming each example or inline value that
failed with its ``file:line`` and traceback, and each one skipped because it reads a name that a
failed one was to define; the output folder is left as it was.  Weaving twice gives the same files.

The weave removes or replaces only files it wrote itself.  ``weave-manifest.json`` in the output
folder lists the files the last weave wrote; a file of an earlier weave that this one does not
write is removed if the manifest lists it or if it is a page or style sheet with the weave's mark
(or a figure or notebook such a page links to: that is how a folder woven before there was a
manifest is read).  Any other file (``docs/daisy/``, ``docs/README.md``, a user's own figure) stays,
and if the weave is to write a file that exists and is not its own, it stops with status 2 naming
``--out`` and the files, changing nothing.  Files are moved into place one by one with ``os.replace``
(none is ever half written); a failure, Ctrl-C or SIGTERM during the move puts back what was there.

Usage::

    python weave.py                  # write docs/
    python weave.py --out /tmp/docs  # somewhere else
    python weave.py --no-notebooks   # pages only

Needs markdown-it-py, mdit-py-plugins, latex2mathml, Pygments, matplotlib and jupytext (the
``docs`` extra of the package).
"""
from __future__ import annotations

import argparse
import ast
import base64
import builtins
import contextlib
import dataclasses
import html
import inspect
import io
import json
import os
import re
import shutil
import struct
import symtable
import sys
import tempfile
import time
import traceback
import warnings
from pathlib import Path

import tangle

GENERATOR = "ident weave.py"
FIGURE_DPI = 110
# Pygments wraps every token in a span; names and punctuation have no rule in the default style, and
# whitespace shows no colour, so their spans only add bytes (a third of the pages' size): unwrapped.
# Operators (= . + ...) are the commonest token after names: the default style's dark grey for them
# (#666) is barely told from the text, and their spans were another eighth of the pages: unwrapped too,
# so they take the text's colour.
UNSTYLED_TOKEN = re.compile(r'<span class="(?:n|p|w|o)">([^<]*)</span>')
IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".gif", ".svg", ".webp"}
MIME = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".gif": "image/gif",
        ".svg": "image/svg+xml", ".webp": "image/webp"}
TEXT_COLUMNS = 88  # characters of code that fit in the text column (45rem in site.css)
TEXT_WIDTH_PX = 720  # the text column in CSS pixels; a wider figure widens its example
FRONT_SECTIONS = {"quick-start"}  # sections that belong to the front matter the index shows
CAPTION = re.compile(r"^\s*#\s*caption:\s*(?P<caption>\S.*?)\s*$")  # in an example: its figure's caption
PLACEHOLDER = "WEAVEREF{}X"
BLOCK_PLACEHOLDER = "WEAVEVALUE{}X"
PLACEHOLDER_HTML = re.compile(r'<span class="[^"]*">WEAVEREF(\d+)X</span>|WEAVEREF(\d+)X')


class WeaveError(Exception):
    """The weave cannot go on; the message names the literate ``file:line``."""


class OptionError(WeaveError):
    """A bad ``--root`` or ``--out`` (the command line exits 2); the message names the option."""


# --------------------------------------------------------------------------------------------
# Cross references between chunks


def slug(text: str, limit: int = 60) -> str:
    """A lower-case id fragment of letters, digits and hyphens."""
    text = re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")
    return text[:limit].rstrip("-") or "x"


def page_name(document_path: str) -> str:
    return Path(document_path).stem + ".html"


@dataclasses.dataclass
class Piece:
    """One chunk block (a definition or a continuation) as woven."""

    block: tangle.Block
    number: int  # 1-based, over all documents in reading order
    anchor: str  # the HTML id
    page: str  # the HTML file holding it
    index: int  # 0 for the definition, k for the k-th continuation


@dataclasses.dataclass
class CrossReferences:
    pieces: dict[tangle.Location, Piece]  # by the location of the opening fence
    by_name: dict[str, list[Piece]]
    uses: dict[str, list[Piece]]  # chunk name -> the pieces that include it, in reading order
    examples: dict[tangle.Location, str]  # example anchors

    def link(self, piece: Piece, from_page: str) -> str:
        return ("" if piece.page == from_page else piece.page) + "#" + piece.anchor


def cross_references(web: tangle.Web) -> CrossReferences:
    pieces: dict[tangle.Location, Piece] = {}
    by_name: dict[str, list[Piece]] = {}
    uses: dict[str, list[Piece]] = {}
    examples: dict[tangle.Location, str] = {}
    taken: set[str] = set()

    def unique(base: str) -> str:
        anchor, k = base, 2
        while anchor in taken:
            anchor, k = f"{base}-{k}", k + 1
        taken.add(anchor)
        return anchor

    number = 0
    for document in web.documents:
        for block in document.items:
            if not isinstance(block, tangle.Block):
                continue
            if block.kind == "example":
                examples[block.location] = unique("example-" + slug(block.name))
            elif block.kind == "chunk":
                number += 1
                siblings = by_name.setdefault(block.name, [])
                base = "chunk-" + slug(block.name) + (f"-{len(siblings) + 1}" if siblings else "")
                piece = Piece(block, number, unique(base), page_name(document.path), len(siblings))
                siblings.append(piece)
                pieces[block.location] = piece
    for piece in pieces.values():
        for _, _, target in tangle.references(piece.block):
            users = uses.setdefault(target, [])
            if not users or users[-1] is not piece:
                users.append(piece)
    return CrossReferences(pieces, by_name, uses, examples)


def reachable(web: tangle.Web, name: str) -> list[str]:
    """Chunk names included, directly or not, by chunk ``name`` (itself first)."""
    order, stack = [], [name]
    while stack:
        current = stack.pop()
        if current in order or current not in web.pieces:
            continue
        order.append(current)
        targets = [t for block in web.pieces[current] for _, _, t in tangle.references(block)]
        stack.extend(reversed(targets))
    return order


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

    def run(self, block: tangle.Block, namespace: dict, base: str) -> Result:
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

    def evaluate(self, value: tangle.InlineValue, namespace: dict, alone: bool) -> str:
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


def run_order(document: tangle.Document) -> list:
    """The examples and inline values of a document in the order they run: reading order, except
    that an inline value that reads a name no example above it binds runs right after the example
    below it that binds the last such name (the text may state a result before the example that
    computes it)."""
    units = document.runnable()
    binds = [module_names("\n".join(u.lines))[0] if isinstance(u, tangle.Block) else set() for u in units]
    order, waiting, seen = [], [], set()  # waiting: [value, the names it still waits for]
    for k, unit in enumerate(units):
        if isinstance(unit, tangle.InlineValue):
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
    if isinstance(unit, tangle.Block):
        return f"example '{unit.name}'"
    return f"inline value `{{python}} {unit.expression}`"


class DocumentRun:
    """Runs a document's examples and inline values in reading order, in one namespace.

    One failure is one failure: a later unit that reads a name the failed one binds (directly, or
    through a unit skipped for that reason) is skipped, naming the failure; the others still run.
    """

    def __init__(self, document: tangle.Document, runner: ExampleRunner, anchors: dict | None = None):
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
        example = isinstance(unit, tangle.Block)
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

    def anchor(self, block: tangle.Block) -> str:
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


# --------------------------------------------------------------------------------------------
# Markdown, mathematics and code


def make_markdown():
    from markdown_it import MarkdownIt
    from mdit_py_plugins.anchors import anchors_plugin
    from mdit_py_plugins.dollarmath import dollarmath_plugin

    md = MarkdownIt("commonmark", {"typographer": False}).enable(["table", "strikethrough"])
    md.use(dollarmath_plugin, allow_labels=False, allow_space=False, allow_digits=False)
    md.use(anchors_plugin, min_level=1, max_level=4)
    return md


MATHML = "http://www.w3.org/1998/Math/MathML"
LIMIT_OPERATORS = {"min", "max", "lim", "sup", "inf", "arg min", "arg max", "argmin", "argmax", "lim sup",
                   "lim inf", "det", "gcd", "Pr"}
UPRIGHT = set("ΓΔΘΛΞΠΣΥΦΨΩ")  # capital Greek is upright in TeX; a one-letter <mi> would be italic
FENCES = set("()[]{}|\u2016\u27e8\u27e9\u2308\u2309\u230a\u230b")
# MathML Core (Chromium) honours mathvariant="normal" only: the other variants become the letters of
# Unicode's Mathematical Alphanumeric Symbols, by name ("MATHEMATICAL SCRIPT CAPITAL K", or for the
# letters Unicode had before, "SCRIPT CAPITAL B", "BLACK-LETTER CAPITAL C", "PLANCK CONSTANT")
VARIANTS = {"bold": "BOLD", "italic": "ITALIC", "bold-italic": "BOLD ITALIC", "script": "SCRIPT",
            "bold-script": "BOLD SCRIPT", "fraktur": "FRAKTUR", "bold-fraktur": "BOLD FRAKTUR",
            "double-struck": "DOUBLE-STRUCK", "sans-serif": "SANS-SERIF", "bold-sans-serif": "SANS-SERIF BOLD",
            "sans-serif-italic": "SANS-SERIF ITALIC", "sans-serif-bold-italic": "SANS-SERIF BOLD ITALIC",
            "monospace": "MONOSPACE"}
# \mathrm{d}: latex2mathml reads a braced letter as the plain letter, which MathML sets in italic
ROMAN_LETTER = re.compile(r"\\mathrm\s*\{\s*([A-Za-z])\s*\}")


def styled(text: str, variant: str) -> str | None:
    """``text`` in the letters of a mathvariant, or None where Unicode has no such letter."""
    import unicodedata

    out = []
    for char in text:
        name = re.sub(r"^(?:LATIN|GREEK) |LETTER ", "", unicodedata.name(char, ""))  # CAPITAL K, DIGIT ONE
        style = VARIANTS.get(variant)
        names = [f"MATHEMATICAL {style} {name}", f"{style} {name}", f"BLACK-LETTER {name}" * (style == "FRAKTUR"),
                 "PLANCK CONSTANT" * ((variant, char) == ("italic", "h"))]
        for candidate in names if name and style else []:
            with contextlib.suppress(KeyError):
                out.append(unicodedata.lookup(candidate))
                break
        else:
            return None
    return "".join(out)


def to_mathml(latex: str, display: bool) -> str:
    """MathML Core for a LaTeX formula, as TeX would set it.

    latex2mathml does the conversion; then, so that browsers set the formula
    as TeX does: a delimiter written without \\left/\\right (``\\lVert x \\rVert^2``) keeps its size
    (MathML would stretch it), except around a matrix; the limits of \\min, \\max, ... go under
    the operator in displayed formulas (``movablelimits`` puts them to the side in running text);
    capital Greek letters stay upright; and the letters of \\mathcal, \\mathbb, \\mathbf, ... are
    Unicode's mathematical letters, braced or not (``\\mathcal K`` is ``\\mathcal{K}``), and those of
    \\mathrm upright.
    """
    import xml.etree.ElementTree as ElementTree

    from latex2mathml.converter import convert

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        latex = ROMAN_LETTER.sub(r"{\\mathrm \1}", latex.strip())
        converted = convert(latex, display="block" if display else "inline")
    ElementTree.register_namespace("", MATHML)
    tree = ElementTree.fromstring(converted)
    tag = lambda name: f"{{{MATHML}}}{name}"  # noqa: E731
    for parent in tree.iter():
        children = list(parent)
        has_table = any(child.tag == tag("mtable") for child in children)
        for child in children:
            if (child.tag == tag("mo") and (child.text or "") in FENCES and "stretchy" not in child.attrib
                    and not has_table):
                child.set("stretchy", "false")
            if child.tag in (tag("msub"), tag("msubsup")) and len(child) and child[0].tag == tag("mo") \
                    and (child[0].text or "").strip() in LIMIT_OPERATORS:
                child.tag = tag("munder" if child.tag == tag("msub") else "munderover")
                child[0].set("movablelimits", "true")
            if child.tag in (tag("mi"), tag("mn")) and child.get("mathvariant", "normal") != "normal":
                letters = styled(child.text or "", child.get("mathvariant"))
                if letters:
                    child.text = letters
                    del child.attrib["mathvariant"]
            if child.tag == tag("mi") and (child.text or "") in UPRIGHT and "mathvariant" not in child.attrib:
                child.set("mathvariant", "normal")
    unknown = sorted({e.text for e in tree.iter() if (e.text or "").startswith("\\") and len(e.text) > 1})
    if unknown:
        raise ValueError("unknown LaTeX command " + ", ".join(unknown))
    return ElementTree.tostring(tree, encoding="unicode")


# --------------------------------------------------------------------------------------------
# The apparatus of a paper: parts, numbered formulas, figures and tables, citations, and links
# between the documents.  Everything numbered is collected from every page (the first pass)
# before any page is rendered (the second), so that a reference may point forward or to another page.


LABEL = r"[A-Za-z0-9_](?:[\w-]|[.:](?=[\w-]))*"  # a label: letters, digits, '_', '-', inner '.' and ':'
KEY = r"\w[\w:.+/-]*"  # a citation key
PART_MARKER = re.compile(r"^<!--\s*part:\s*(?P<title>\S.*?)\s*-->$")
EQUATION_LABEL = re.compile(rf"\$\$[ \t]*\{{#eq:(?P<name>{LABEL})\}}[ \t]*$")  # after a formula's closing $$
EQUATION_TAG = re.compile(r"\\tag\s*\{(?P<tag>[^{}]*)\}")
NO_NUMBER = re.compile(r"\\(?:notag|nonumber)(?![A-Za-z])")
FIGURE_LABEL = re.compile(rf"\s*\{{#fig:(?P<name>{LABEL})\}}$")  # at the end of a # caption: line
TABLE_CAPTION = re.compile(r"^Table:\s*")
TABLE_LABEL = re.compile(rf"\s*\{{#tbl:(?P<name>{LABEL})\}}\s*$")
BIBLIOGRAPHY_ENTRY = re.compile(rf"^\{{#ref:(?P<key>{KEY})\}}\s*")
# a mention of a literate document by its file name (NN-name.md), with a heading's anchor or not
MENTION = re.compile(r"(?<![\w/.-])(?:literate/)?(?P<name>\d\d[\w-]*\.md)(?:#(?P<anchor>[\w-]+))?(?![\w-])")
# a mention of a file or folder of the repository outside literate/ (reference/README.md, benchmarks/x.py)
REPOSITORY_PATH = re.compile(r"(?<![\w/.-])(?P<path>(?:reference|benchmarks|tests|src|docs)(?:/[\w.-]*\w)+/?)(?![\w/-])")
IN_TEXT = re.compile(rf"\[(?P<keys>@{KEY}(?:\s*;\s*@{KEY})*)\]"  # [@KEY] or [@KEY1; @KEY2]
                     rf"|(?<![\w@])@(?P<kind>eq|fig|tbl):(?P<label>{LABEL})"  # @eq:NAME, @fig:NAME, @tbl:NAME
                     rf"|{MENTION.pattern}|{REPOSITORY_PATH.pattern}")
CODE_TEXT = re.compile(r'(<span class="[cs][a-z0-9]*">)(.*?)(</span>)', re.S)  # comments and strings (Pygments)


@dataclasses.dataclass
class Target:
    """Something a reference can point to: a formula, figure, table or bibliography entry."""

    page: str
    anchor: str
    text: str  # what a reference to it reads: "(7)", "Figure 3", "Table 2", or the entry's number
    location: str  # the file:line of its label


class Apparatus:
    """The labels and numbers of the whole document, collected before any page is rendered."""

    def __init__(self):
        self.targets: dict[str, Target] = {}  # "eq:NAME", "fig:NAME", "tbl:NAME", "ref:KEY"
        self.counts: dict[str, int] = {"eq": 0, "fig": 0, "tbl": 0, "ref": 0}
        self.cited: set[str] = set()
        self.titles: dict[str, str] = {}  # the stem of a document -> its title as plain text

    def next(self, kind: str) -> int:
        self.counts[kind] += 1
        return self.counts[kind]

    def define(self, label: str, target: Target) -> None:
        if label in self.targets:
            raise WeaveError(f"{target.location}: duplicate label {{#{label}}} "
                             f"(first at {self.targets[label].location})")
        self.targets[label] = target

    def find(self, label: str, location: str) -> Target:
        if label not in self.targets:
            what = "bibliography entry" if label.startswith("ref:") else "label"
            raise WeaveError(f"{location}: unknown {what} {label.removeprefix('ref:')!r}")
        if label.startswith("ref:"):
            self.cited.add(label)
        return self.targets[label]

    def uncited(self) -> list[str]:
        return [f"{target.location}: warning: bibliography entry {label.removeprefix('ref:')!r} is never cited"
                for label, target in self.targets.items() if label.startswith("ref:") and label not in self.cited]


def part_marker(document: tangle.Document) -> tuple[int, str] | None:
    """(line, title) of the part a document opens: its first non-blank line ``<!-- part: TITLE -->``."""
    for number, line in document.text_lines():
        if line.strip():
            match = PART_MARKER.match(line.strip())
            return (number, match["title"]) if match else None
    return None


def figure_captions(block: tangle.Block) -> list[tuple[int, str, str | None]]:
    """(line, caption, label) of each ``# caption:`` line of an example, the label stripped."""
    found = []
    for line, text in enumerate(block.lines, start=block.body_location.line):
        match = CAPTION.match(text)
        if match:
            label = FIGURE_LABEL.search(match["caption"])
            caption = match["caption"][:label.start()] if label else match["caption"]
            found.append((line, caption, label["name"] if label else None))
    return found


def html_token(content: str, inline: bool = False, **meta):
    from markdown_it.token import Token

    return Token("html_inline" if inline else "html_block", "", 0, content=content, meta=meta)


class PageRenderer:
    """Renders one literate document to HTML with markdown-it, MathML and Pygments."""

    def __init__(self, weave: "Weave", document: tangle.Document, results: dict):
        from pygments.formatters import HtmlFormatter

        self.weave = weave
        self.document = document
        self.page = page_name(document.path)
        self.results = results
        self.formatter = HtmlFormatter(nowrap=True)
        self.blocks = {b.location.line: b for b in document.items if isinstance(b, tangle.Block)}
        self.rendered: set[int] = set()
        self.figures: dict[tangle.Location, list] = {}  # example -> (number, anchor, caption) per figure
        self.tokens: list = []  # the page as markdown-it tokens, from the first pass
        self.title = Path(self.page).stem
        self.md = make_markdown()
        rules = self.md.renderer.rules  # bound methods: add_render_rule would rebind them to the renderer
        rules["fence"] = self.render_fence
        rules["code_block"] = self.render_code_block
        rules["math_inline"] = self.render_math
        rules["math_block"] = self.render_math
        rules["link_open"] = self.render_link_open
        self.apparatus: Apparatus = weave.apparatus

    # markdown-it render rules: (tokens, idx, options, env) as bound methods
    def render_fence(self, tokens, idx, options, env) -> str:
        token = tokens[idx]
        line = token.map[0] + 1 if token.map else None
        block = self.blocks.get(line)
        if block is None:
            language = tangle.parse_info(token.info)[0] or "text"
            return self.highlight_block(token.content.rstrip("\n").split("\n"), language)
        self.rendered.add(line)
        if block.kind == "chunk":
            return self.render_chunk(block)
        if block.kind == "example":
            return self.render_example(block)
        return self.highlight_block(block.lines, tangle.parse_info(block.info)[0] or "text")

    def render_code_block(self, tokens, idx, options, env) -> str:
        content = tokens[idx].content
        return f'<pre class="plain{wide(content.splitlines())}"><code>{html.escape(content)}</code></pre>\n'

    def render_math(self, tokens, idx, options, env) -> str:
        token = tokens[idx]
        display = token.type == "math_block"
        try:
            mathml = to_mathml(token.content, display)
        except Exception as error:  # latex2mathml raises various exceptions on unknown LaTeX
            line = token.meta.get("line") or (token.map[0] + 1 if token.map else "?")
            self.weave.warn(f"{self.document.path}:{line}: warning: cannot convert "
                            f"${token.content.strip()}$ to MathML ({type(error).__name__}: {error})")
            mathml = f'<code class="math-error">{html.escape(token.content)}</code>'
        if not display:
            return mathml
        anchor, shown = token.meta.get("equation", (None, None))
        if shown is None:
            return f'<div class="math-display">{mathml}</div>\n'
        where = f' id="{anchor}"' if anchor else ""
        return (f'<div class="equation"{where}><div class="math-display">{mathml}</div>'
                f'<span class="equation-number">{html.escape(shown)}</span></div>\n')

    def render_link_open(self, tokens, idx, options, env) -> str:
        token = tokens[idx]
        href = token.attrGet("href") or ""
        target, hash_, fragment = href.partition("#")
        if target.endswith(".md") and "://" not in target:
            stem = Path(target).stem
            if stem in self.weave.stems:
                token.attrSet("href", f"{stem}.html" + (hash_ + fragment))
            elif MENTION.fullmatch(Path(target).name):
                self.weave.warn(f"{self.document.path}:{token.meta.get('line', '?')}: warning: a link to "
                                f"{target}, which is not a literate document")
        return self.md.renderer.renderToken(tokens, idx, options, env)

    # pieces of the page
    def highlight(self, text: str, language: str) -> str:
        from pygments import highlight
        from pygments.lexers import TextLexer, get_lexer_by_name
        from pygments.util import ClassNotFound

        try:
            lexer = get_lexer_by_name(language, stripnl=False, ensurenl=True)
        except ClassNotFound:
            lexer = TextLexer(stripnl=False, ensurenl=True)
        code = UNSTYLED_TOKEN.sub(r"\1", highlight(text, lexer, self.formatter))
        return CODE_TEXT.sub(lambda m: m[1] + MENTION.sub(self.code_mention, m[2]) + m[3], code)

    def code_mention(self, match: re.Match) -> str:
        """A literate document named in a comment or string of code: a link, the text unchanged."""
        stem = Path(match["name"]).stem
        if stem not in self.weave.stems:
            return match[0]
        return f'<a href="{stem}.html{"#" + match["anchor"] if match["anchor"] else ""}">{match[0]}</a>'

    def highlight_block(self, lines: list[str], language: str, widen: bool = True) -> str:
        lines = trim_blank(lines)
        code = self.highlight("\n".join(lines), language).rstrip()
        return f'<pre class="highlight{wide(lines) if widen else ""}"><code>{code}</code></pre>\n'

    def render_chunk(self, block: tangle.Block) -> str:
        xref = self.weave.xref
        piece = xref.pieces[block.location]
        names, lines = [], []
        for line in trim_blank(block.lines):
            match = tangle.REFERENCE.match(line)
            if match:
                names.append(tangle.normalise_name(match["name"]))
                lines.append(match["indent"] + PLACEHOLDER.format(len(names) - 1))
            else:
                lines.append(line)
        code = self.highlight("\n".join(lines), "python").rstrip()

        def reference(match: re.Match) -> str:
            target = names[int(match[1] or match[2])]
            definition = xref.by_name[target][0]
            return (f'<span class="chunk-ref">⟨<a href="{xref.link(definition, self.page)}">'
                    f'{chunk_title(target)}</a>&#x2009;<span class="chunk-num">{definition.number}</span>'
                    "⟩</span>")

        code = PLACEHOLDER_HTML.sub(reference, code)
        operator = "+≡" if block.continued else "≡"
        head = (f'<div class="chunk-head"><a class="chunk-num" href="#{piece.anchor}" '
                f'title="{html.escape(str(block.location))}">{piece.number}</a> '
                f'<span class="chunk-name">⟨{chunk_title(block.name)}⟩</span>'
                f'<span class="chunk-op">{operator}</span></div>')
        return (f'<div class="chunk{wide(lines)}" id="{piece.anchor}">\n{head}\n'
                f'<pre class="highlight"><code>{code}</code></pre>\n{self.chunk_notes(piece)}</div>\n')

    def chunk_notes(self, piece: Piece) -> str:
        xref, name = self.weave.xref, piece.block.name
        siblings = xref.by_name[name]
        notes = []
        if piece.index > 0:
            notes.append("Defined in " + self.piece_link(siblings[0]) + ".")
        if piece.index + 1 < len(siblings):
            later = siblings[piece.index + 1:]
            notes.append("Continued in " + ", ".join(self.piece_link(p) for p in later) + ".")
        if tangle.is_root(name):
            if piece.index == 0:
                notes.append(f"Root chunk: written to <code>{html.escape(name)}</code>.")
        elif name in xref.uses:
            notes.append("Used in " + ", ".join(self.piece_link(p, with_name=True) for p in xref.uses[name]) + ".")
        elif piece.index == 0:
            notes.append("Not used by any chunk.")
        return f'<p class="chunk-notes">{" ".join(notes)}</p>\n' if notes else ""

    def piece_link(self, piece: Piece, with_name: bool = False) -> str:
        where = "" if piece.page == self.page else f" <span class=\"chunk-page\">({Path(piece.page).stem})</span>"
        href = self.weave.xref.link(piece, self.page)
        if with_name:
            return (f'<a href="{href}">⟨{chunk_title(piece.block.name)}⟩&#x2009;'
                    f'<span class="chunk-num">{piece.number}</span></a>{where}')
        return f'<a href="{href}">{piece.number}</a>{where}'

    def render_example(self, block: tangle.Block) -> str:
        anchor = self.weave.xref.examples[block.location]
        result = self.results.get(block.location)
        code = [line for line in block.lines if not CAPTION.match(line)]  # a caption shows under its figure
        lines = code + (result.stdout.splitlines() + result.stderr.splitlines() if result else [])
        large = result is not None and any((f.width or 0) > TEXT_WIDTH_PX for f in result.figures)
        parts = [f'<div class="example{" wide" if large else wide(lines)}" id="{anchor}">',
                 f'<div class="example-head"><a href="#{anchor}" title="{html.escape(str(block.location))}">'
                 f'Example</a>: {html.escape(block.name)}</div>',
                 self.highlight_block(code, "python", widen=False).rstrip("\n")]
        if result is not None:
            if result.stdout:
                parts.append(f'<pre class="output" aria-label="output">'
                             f"{html.escape(result.stdout.rstrip())}</pre>")
            if result.stderr:
                parts.append(f'<pre class="output stderr" aria-label="standard error">'
                             f'{html.escape(result.stderr.rstrip())}</pre>')
            for figure, numbered in zip(result.figures, self.figures[block.location]):
                parts.append(self.render_figure(figure, *numbered))
        parts.append("</div>")
        return "\n".join(parts) + "\n"

    def render_figure(self, figure: Figure, number: int | None, anchor: str, caption: str, line: int) -> str:
        """A figure with its number in the document and its caption (Markdown, from ``# caption:``)."""
        source = html.escape(figure.path)
        if number is None:
            return f'<p class="figure-link"><a href="{source}">{html.escape(Path(figure.path).name)}</a></p>'
        size = f' width="{figure.width}" height="{figure.height}"' if figure.width and figure.height else ""
        tokens = self.md.parseInline(caption, {})
        self.link_text(tokens[0].children or [], line)
        text = self.md.renderer.render(tokens, self.md.options, {})
        alt = re.sub(r"<[^>]+>", "", text)
        return (f'<figure class="example-figure" id="{anchor}"><a href="{source}"><img src="{source}"{size} '
                f'alt="{html.escape(alt)}"></a><figcaption><span class="figure-number">Figure {number}.</span> '
                f"{text}</figcaption></figure>")

    # the first pass: parse the page, number what it holds and register the labels
    def prepare(self) -> None:
        """Parse the page and number its formulas, figures, captioned tables and bibliography entries."""
        text, values = self.weave.text_with_values(self.document.path, marked=True)
        lines, labels = text.split("\n"), {}
        marker = part_marker(self.document)
        if marker:  # the part shows above the title, not as a comment
            lines[marker[0] - 1] = ""
        for number, _ in self.document.text_lines():
            match = EQUATION_LABEL.search(lines[number - 1])
            if match:
                labels[number] = match["name"]
                lines[number - 1] = lines[number - 1][:match.start()] + "$$"
        tokens = self.splice_values(self.md.parse("\n".join(lines), {}), values)
        for token in tokens:  # inline tokens have no line of their own: give them their block's
            if token.children and token.map:
                for child in token.children:
                    child.meta = dict(child.meta or {}, line=token.map[0] + 1)
        self.tokens = self.caption_tables(tokens)
        self.number_equations(labels)
        self.number_figures()
        self.number_bibliography()
        title = next((k for k, t in enumerate(self.tokens) if t.type == "heading_open" and t.tag == "h1"), None)
        if title is not None:
            self.title = plain_title(self.tokens[title + 1])
        self.apparatus.titles[Path(self.page).stem] = self.title
        for block in self.blocks.values():  # code naming a document that is not one (links: render_link_open)
            for line, text in enumerate(block.lines, start=block.body_location.line):
                for match in MENTION.finditer(text):
                    self.check_mention(match, line)

    def splice_values(self, tokens: list, values: list[tuple[str, str]]) -> list:
        """The tokens with each value of several lines parsed as Markdown in place of its paragraph."""
        for k, (expression, value) in enumerate(values):
            placeholder = BLOCK_PLACEHOLDER.format(k)
            at = next((i for i, t in enumerate(tokens) if i and t.type == "inline" and t.content == placeholder
                       and tokens[i - 1].type == "paragraph_open"), None)
            if at is None:
                raise WeaveError(f"{self.document.path}: the value of `{{python}} {expression}` has several "
                                 "lines; give it a paragraph of its own (blank lines before and after)")
            inner = self.md.parse(value, {})
            for token in inner:
                token.map = tokens[at].map
            tokens[at - 1:at + 2] = [html_token(f'<div class="computed" title="{html.escape(expression)}">\n'),
                                     *inner, html_token("</div>\n", value_end=True)]
        return tokens

    def caption_tables(self, tokens: list) -> list:
        """A table followed by a paragraph ``Table: caption {#tbl:NAME}`` gets it as its numbered caption."""
        out, table, k = [], 0, 0
        while k < len(tokens):
            out.append(tokens[k])
            k += 1
            if out[-1].type == "table_open":
                table = len(out) - 1
            if out[-1].type != "table_close":
                continue
            after = k
            while after < len(tokens) and tokens[after].meta.get("value_end"):  # a table that is a value
                after += 1
            if not (after + 2 < len(tokens) and tokens[after].type == "paragraph_open"
                    and TABLE_CAPTION.match(tokens[after + 1].content)):
                continue
            out += tokens[k:after]
            inline, k = tokens[after + 1], after + 3
            children = inline.children
            children[0].content = TABLE_CAPTION.sub("", children[0].content, count=1)
            label = TABLE_LABEL.search(children[-1].content) if children[-1].type == "text" else None
            if label:
                children[-1].content = children[-1].content[:label.start()]
            number = self.apparatus.next("tbl")
            anchor = f"tbl-{label['name']}" if label else f"table-{number}"
            if label:
                self.apparatus.define("tbl:" + label["name"], Target(
                    self.page, anchor, f"Table {number}", f"{self.document.path}:{inline.map[0] + 1}"))
            out[table].attrSet("id", anchor)
            out[table + 1:table + 1] = [html_token(f'<caption><span class="table-number">Table {number}.</span> '),
                                        inline, html_token("</caption>\n")]
        for k, token in enumerate(out):
            if token.type == "inline" and TABLE_CAPTION.match(token.content) and out[k - 1].type == "paragraph_open":
                self.weave.warn(f"{self.document.path}:{token.map[0] + 1}: warning: a 'Table:' caption that "
                                "follows no table (it belongs right after its table, after one blank line)")
        return out

    def number_equations(self, labels: dict[int, str]) -> None:
        """Number the display formulas; ``\\tag{NAME}`` shows (NAME), ``\\notag`` no number."""
        for token in self.tokens:
            if token.type != "math_block":
                continue
            name = labels.pop(token.map[1], None) if token.map else None
            tag, plain = EQUATION_TAG.search(token.content), NO_NUMBER.search(token.content)
            token.content = NO_NUMBER.sub("", EQUATION_TAG.sub("", token.content))
            shown = f"({tag['tag'].strip()})" if tag else None if plain else f"({self.apparatus.next('eq')})"
            anchor = f"eq-{name}" if name else None
            if name:
                location = f"{self.document.path}:{token.map[1]}"
                if shown is None:
                    raise WeaveError(f"{location}: the formula labelled {{#eq:{name}}} has no number (\\notag)")
                self.apparatus.define("eq:" + name, Target(self.page, anchor, shown, location))
            token.meta = dict(token.meta or {}, equation=(anchor, shown))
        for line, name in labels.items():
            raise WeaveError(f"{self.document.path}:{line}: the label {{#eq:{name}}} closes no display formula "
                             "(write it after the closing $$)")

    def number_figures(self) -> None:
        """Number the figures of the examples; a caption ending in ``{#fig:NAME}`` labels its figure."""
        for token in self.tokens:
            block = self.blocks.get(token.map[0] + 1) if token.type == "fence" and token.map else None
            if block is None or block.kind != "example":
                continue
            result = self.results.get(block.location)
            figures = result.figures if result else []
            captions = figure_captions(block)
            numbered = []
            for k, figure in enumerate(figures):
                line, caption, name = captions[k] if k < len(captions) else (block.location.line, block.name, None)
                number = self.apparatus.next("fig") if Path(figure.path).suffix.lower() in IMAGE_SUFFIXES else None
                anchor = f"fig-{name}" if name else f"figure-{number}"
                if name and number:
                    self.apparatus.define("fig:" + name, Target(self.page, anchor, f"Figure {number}",
                                                                f"{self.document.path}:{line}"))
                numbered.append((number, anchor, caption, line))
            for line, _, name in captions[len(figures):]:
                if name:
                    raise WeaveError(f"{self.document.path}:{line}: the caption labelled {{#fig:{name}}} has no "
                                     f"figure (the example drew {len(figures)})")
            self.figures[block.location] = numbered

    def number_bibliography(self) -> None:
        """Number the list items that begin with ``{#ref:KEY}``, the entries of a bibliography."""
        for k, token in enumerate(self.tokens):
            inline = self.tokens[k + 2] if token.type == "list_item_open" and k + 2 < len(self.tokens) else None
            match = BIBLIOGRAPHY_ENTRY.match(inline.content) if inline and inline.type == "inline" else None
            if not match or not inline.children or inline.children[0].type != "text":
                continue
            number, key = self.apparatus.next("ref"), match["key"]
            self.apparatus.define("ref:" + key, Target(self.page, f"ref-{key}", str(number),
                                                       f"{self.document.path}:{inline.map[0] + 1}"))
            token.attrSet("id", f"ref-{key}")
            inline.children[0].content = BIBLIOGRAPHY_ENTRY.sub("", inline.children[0].content, count=1)
            inline.children.insert(0, html_token(f'<span class="ref-number">[{number}]</span> ', inline=True))
            for opening in reversed(self.tokens[:k]):  # the list it is in
                if opening.type in ("bullet_list_open", "ordered_list_open") and opening.level == token.level - 1:
                    opening.attrSet("class", "bibliography")
                    break

    # the second pass: references become links
    def link_text(self, children: list, line: int | None = None) -> None:
        """Citations, references to labels and mentions of documents in inline tokens become links
        (not inside links)."""
        from markdown_it.common.utils import escapeHtml

        depth = 0
        for child in children:
            depth += (child.type == "link_open") - (child.type == "link_close")
            where = f"{self.document.path}:{line or child.meta.get('line', '?')}"
            if depth or child.type not in ("text", "code_inline"):
                continue
            if child.type == "code_inline":
                match = MENTION.fullmatch(child.content)
                if match and self.check_mention(match, line or child.meta.get("line", "?")):
                    child.type, child.content = "html_inline", self.reference(match, where)
                elif (match := REPOSITORY_PATH.fullmatch(child.content)) and self.repository_href(match["path"]):
                    child.type, child.content = "html_inline", self.reference(match, where, code=True)
                continue
            pieces, last = [], 0
            for match in IN_TEXT.finditer(child.content):
                if match["name"] and not self.check_mention(match, line or child.meta.get("line", "?")):
                    continue
                if match["path"] and not self.repository_href(match["path"]):
                    continue
                pieces += [escapeHtml(child.content[last:match.start()]), self.reference(match, where)]
                last = match.end()
            if pieces:
                child.type, child.content = "html_inline", "".join(pieces) + escapeHtml(child.content[last:])

    def check_mention(self, match: re.Match, line) -> bool:
        """Whether a mention names a literate document; a warning if not."""
        if Path(match["name"]).stem in self.weave.stems:
            return True
        self.weave.warn(f"{self.document.path}:{line}: warning: {match['name']} is not a literate document")
        return False

    def repository_href(self, path: str) -> str | None:
        """The link from the woven pages to a file of the repository, or None where there is none (a
        reader of the pages in a clone opens it; a folder, or a path that does not exist, stays text).
        Relative to the repository's docs/, where the pages live, whatever folder this weave writes (so
        that two weaves write the same bytes)."""
        docs = self.weave.root / "docs"
        target = self.weave.root / path
        if path.startswith("docs/") and (self.weave.out / path.removeprefix("docs/")).is_file():
            target = docs / path.removeprefix("docs/")  # one of the files this weave writes
        if not target.is_file():
            return None
        return Path(os.path.relpath(target, docs)).as_posix()

    def reference(self, match: re.Match, where: str, code: bool = False) -> str:
        """The HTML of a citation, a reference to a label, or a mention of a document or a file."""
        groups = match.groupdict()
        if groups.get("path"):
            text = html.escape(match["path"])
            return (f'<a class="file" href="{html.escape(self.repository_href(match["path"]))}">'
                    + (f"<code>{text}</code>" if code else text) + "</a>")
        if groups.get("keys"):
            targets = [self.apparatus.find("ref:" + key, where) for key in re.findall(rf"@({KEY})", match["keys"])]
            return "[" + ", ".join(f'<a class="citation" href="{t.page}#{t.anchor}">{t.text}</a>'
                                   for t in targets) + "]"
        if groups.get("kind"):
            target = self.apparatus.find(f"{match['kind']}:{match['label']}", where)
            return f'<a class="xref" href="{target.page}#{target.anchor}">{html.escape(target.text)}</a>'
        stem = Path(match["name"]).stem
        anchor = "#" + match["anchor"] if match["anchor"] else ""
        return f'<a class="document" href="{stem}.html{anchor}">{html.escape(self.apparatus.titles[stem])}</a>'

    def render(self) -> "Page":
        tokens = self.tokens
        for k, token in enumerate(tokens):
            if token.type == "inline" and token.children and not (k and tokens[k - 1].type == "heading_open"):
                self.link_text(token.children)
        env: dict = {}
        headings = []
        for k, token in enumerate(tokens):
            if token.type == "heading_open":
                inline = tokens[k + 1]
                label = self.md.renderer.renderInline(inline.children or [], self.md.options, env)
                headings.append((int(token.tag[1]), token.attrGet("id"), label, plain_title(inline)))
        title_end = next((k for k, t in enumerate(tokens) if t.type == "heading_close" and t.tag == "h1"), -1)
        part = self.weave.parts.get(self.document.path)
        head = f'<div class="part-name">{html.escape(part)}</div>\n' if part else ""
        head += self.md.renderer.render(tokens[:title_end + 1], self.md.options, env)
        body = self.md.renderer.render(tokens[title_end + 1:], self.md.options, env)
        missing = [b for line, b in self.blocks.items() if b.kind != "display" and line not in self.rendered]
        if missing:
            raise WeaveError(f"{missing[0].location}: the Markdown parser did not read this {missing[0].kind} "
                             "as a fenced code block; start its fence at column 0 outside lists and quotes")
        headings = [(level, anchor, label) for level, anchor, label, _ in headings]
        first_section = next((k for k, t in enumerate(tokens) if k > title_end and t.type == "heading_open"
                              and t.tag == "h2" and t.attrGet("id") not in FRONT_SECTIONS), len(tokens))
        front = self.md.renderer.render(tokens[title_end + 1:first_section], self.md.options, env)
        return Page(self.document, self.page, self.title, headings, head, body, front)


def wide(lines: list[str]) -> str:
    """" wide" (a class) for code with lines longer than the text column holds."""
    return " wide" if any(len(line.expandtabs(4)) > TEXT_COLUMNS for line in lines) else ""


def trim_blank(lines: list[str]) -> list[str]:
    start, end = 0, len(lines)
    while start < end and not lines[start].strip():
        start += 1
    while end > start and not lines[end - 1].strip():
        end -= 1
    return lines[start:end]


def chunk_title(name: str) -> str:
    """A chunk name as HTML: file names in code type, the rest as text."""
    return f"<code>{html.escape(name)}</code>" if tangle.is_root(name) else html.escape(name)


def plain_title(inline) -> str:
    """A heading as plain text (for <title> and the navigation): formulas as their LaTeX source."""
    return "".join(child.content for child in inline.children or []
                   if child.type in ("text", "code_inline", "math_inline")).strip()


@dataclasses.dataclass
class Page:
    document: tangle.Document
    file: str
    title: str
    headings: list[tuple[int, str, str]]  # level, id, label (HTML)
    head: str  # the HTML up to and including the title
    body: str
    front: str = ""  # the HTML between the title and the first section (a quick start counts as front)


# --------------------------------------------------------------------------------------------
# The whole weave


STYLE_FILE = Path(__file__).resolve().parent / "literate_tools" / "site.css"  # the page style, read when weaving


# after the Pygments rules, which they adjust: docstrings read as text, not as loud strings
PYGMENTS_OVERRIDES = """\
.highlight .sd { color: #3e6b47; font-style: normal; }
"""


# --------------------------------------------------------------------------------------------
# The output folder: the weave removes or replaces only files it wrote itself

MANIFEST = "weave-manifest.json"  # in the output folder: the files the last weave wrote there
GENERATOR_META = f'<meta name="generator" content="{GENERATOR}">'
STYLE_MARK = f"/* Generated by {GENERATOR}. */"
OUTPUT_LINK = re.compile(r'(?:src|href)="((?:figures|notebooks)/[^"#?]+)"')  # a page's figures, notebook


def weave_like(name: str) -> bool:
    """Whether ``name`` (relative to the output folder) is a name the weave gives: a page
    ``NAME.html`` or ``style.css`` at the top, a file under ``figures/``, ``notebooks/NAME.ipynb``."""
    parts = name.split("/")
    if "\\" in name or any(part in ("", ".", "..") for part in parts):
        return False
    if len(parts) == 1:
        return name == "style.css" or name.endswith(".html")
    return parts[0] == "figures" or (parts[0] == "notebooks" and len(parts) == 2 and name.endswith(".ipynb"))


def carries_mark(path: Path, name: str) -> bool:
    """A page or the style sheet at the top of the output folder must carry the weave's mark near its
    start (a user's page of the same name does not); other files have no mark to check."""
    if "/" in name or not name.endswith((".html", ".css")):
        return True
    with path.open(encoding="utf-8", errors="replace") as handle:
        start = handle.read(2000)
    return GENERATOR_META in start if name.endswith(".html") else start.startswith(STYLE_MARK)


def manifest_text(names) -> str:
    """The manifest: the generator and the sorted file names, nothing that changes between runs."""
    return json.dumps({"generator": GENERATOR, "files": sorted(names)}, indent=1) + "\n"


def read_manifest(out: Path, warn) -> list[str] | None:
    """The files an earlier weave's manifest lists, None if there is none; a manifest that cannot be
    read or is not the weave's is a warning, and then it lists nothing."""
    path = out / MANIFEST
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        files = data["files"] if isinstance(data, dict) and data.get("generator") == GENERATOR else None
    except (OSError, UnicodeDecodeError, ValueError, KeyError) as error:
        files, reason = None, str(error)
    else:
        reason = 'not {"generator": "' + GENERATOR + '", "files": [...]}'
    if not isinstance(files, list) or not all(isinstance(name, str) for name in files):
        warn(f"weave: warning: {path}: not a manifest of the weave ({reason}); no file there is removed "
             "or replaced unless it carries the weave's mark or a page with the mark links to it")
        return None
    strange = [name for name in files if not weave_like(name)]
    if strange:
        warn(f"weave: warning: {path} lists names the weave does not write, left alone: {', '.join(strange[:5])}")
    return [name for name in files if weave_like(name)]


WEAVE_TEMPORARY_SUFFIX = ".weave-new"  # .NAME.weave-new beside NAME while it is written


def remove_leftover_temporaries(out: Path) -> None:
    """Remove the temporaries of ``replace_bytes`` that a killed weave left (only names it gives)."""
    for path in out.rglob(f".*{WEAVE_TEMPORARY_SUFFIX}"):
        folder, _, base = path.relative_to(out).as_posix().removesuffix(WEAVE_TEMPORARY_SUFFIX).rpartition("/")
        name = (folder + "/" if folder else "") + base.removeprefix(".")
        if (weave_like(name) or name == MANIFEST) and path.is_file() and not path.is_symlink():
            with contextlib.suppress(OSError):  # housekeeping: one it cannot remove does no harm
                path.unlink()


def replace_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary beside it (tangle's, with the weave's suffix)."""
    tangle.replace_bytes(path, data, WEAVE_TEMPORARY_SUFFIX)


class Weave:
    def __init__(self, root: Path, out: Path, notebooks: bool = True):
        self.root = root.resolve()
        self.out = out.resolve()
        self.notebooks = notebooks
        self.warnings: list[str] = []
        self.math_count = 0
        # the text is read once: pages, examples and notebooks all come from this snapshot
        self.texts = {relative: tangle.read_literate(path, relative).removeprefix("\ufeff")
                      for path in tangle.literate_files(self.root)
                      for relative in [path.relative_to(self.root).as_posix()]}
        self.web = tangle.build_web([tangle.parse_document(text, path) for path, text in self.texts.items()])
        self.xref = cross_references(self.web)
        self.stems = {Path(d.path).stem for d in self.web.documents}
        self.parts = self.find_parts()  # document -> the title of the part it belongs to (or None)
        self.apparatus = Apparatus()
        self.values: dict[str, dict] = {}  # document -> (line, start, end) of an inline value -> its text

    def text_with_values(self, path: str, marked: bool) -> tuple[str, list[tuple[str, str]]]:
        """A document's text with each inline value replaced by its value, and the values of several
        lines.  ``marked`` (for the page): a value inside a span whose title is the expression, so
        that the page tells where a number comes from, and a value of several lines as a placeholder
        line (the lines of the page must stay those of the text), with its (expression, Markdown)."""
        lines = self.texts[path].replace("\r\n", "\n").replace("\r", "\n").split("\n")
        blocks = []
        for (line, start, end), value in sorted(self.values.get(path, {}).items(), reverse=True):
            expression = tangle.INLINE_VALUE.match(lines[line - 1], start)["expression"].strip()
            if not marked:
                shown = value
            elif "\n" in value:
                shown = BLOCK_PLACEHOLDER.format(len(blocks))
                blocks.append((expression, value))
            else:
                shown = f'<span class="computed" title="{html.escape(expression)}">{value}</span>'
            lines[line - 1] = lines[line - 1][:start] + shown + lines[line - 1][end:]
        return "\n".join(lines), blocks

    def find_parts(self) -> dict[str, str | None]:
        """The part of each document: the one its part marker opens, or the one before it."""
        parts, current = {}, None
        for document in self.web.documents:
            marker = part_marker(document)
            current = marker[1] if marker else current
            parts[document.path] = current
            for number, line in document.text_lines():
                if PART_MARKER.match(line.strip()) and (not marker or number != marker[0]):
                    self.warn(f"{document.path}:{number}: warning: a part marker is read only on the first "
                              "line of a document, before its title; this one is ignored")
        return parts

    def warn(self, message: str) -> None:
        if message in self.warnings:
            return
        self.warnings.append(message)
        print(message, file=sys.stderr)

    def run(self) -> dict:
        """Weave into a new folder beside the output folder; install it only if every example ran."""
        started = time.perf_counter()
        outputs, _ = tangle.tangle(self.root)
        stale = tangle.differences(self.root, outputs)
        if stale:
            self.warn("weave: warning: src/ident is out of date with literate/ (run python tangle.py); "
                      "the examples run against it: " + "; ".join(stale))
        self.refuse_foreign(self.foreseen_outputs(), self.previous_outputs())  # before minutes of examples
        self.out.parent.mkdir(parents=True, exist_ok=True)
        self.build = Path(tempfile.mkdtemp(prefix=f".{self.out.name}-weave-", dir=self.out.parent))
        try:
            summary = self.weave_into_build()
            self.install()
        finally:
            shutil.rmtree(self.build, ignore_errors=True)
        summary["seconds"] = time.perf_counter() - started
        return summary

    def run_examples(self) -> dict[str, DocumentRun]:
        """Every document's examples and inline values; a WeaveError naming each one that failed."""
        runner = ExampleRunner(self.root, self.build)
        runs, problems = {}, []
        for document in self.web.documents:
            runs[document.path] = DocumentRun(document, runner, self.xref.examples)
            runs[document.path].run_all()
            problems += runs[document.path].problems()
        if problems:
            raise WeaveError(f"{len(problems)} example(s) or inline value(s) did not run; docs/ is left as "
                             "it was:\n" + "\n".join(problems))
        return runs

    def weave_into_build(self) -> dict:
        (self.build / "figures").mkdir()
        with example_environment(self.root, self.build / "figures"):
            runs = self.run_examples()
            api = self.public_names()
        results = {path: {unit.location: outcome.result for unit, outcome in zip(run.units, run.outcomes)
                          if isinstance(unit, tangle.Block)} for path, run in runs.items()}
        self.values = {path: {(unit.location.line, unit.start, unit.end): outcome.value
                              for unit, outcome in zip(run.units, run.outcomes)
                              if isinstance(unit, tangle.InlineValue)} for path, run in runs.items()}
        renderers = [PageRenderer(self, d, results[d.path]) for d in self.web.documents]
        for renderer in renderers:  # every label is known before any page is rendered
            renderer.prepare()
        pages = [renderer.render() for renderer in renderers]
        for warning in self.apparatus.uncited():
            self.warn(warning)
        self.write("style.css", self.stylesheet())
        for k, page in enumerate(pages):
            previous = pages[k - 1] if k > 0 else None
            following = pages[k + 1] if k + 1 < len(pages) else None
            self.write(page.file, self.page_html(page, previous, following))
        self.write("index.html", self.index_html(pages, api))
        notebooks = []
        if self.notebooks:
            for document in self.web.documents:
                notebook = self.write_notebook(document, results[document.path])
                if notebook:
                    notebooks.append(notebook)
        figures = sum(len(r.figures) for by_doc in results.values() for r in by_doc.values())
        self.math_count = sum(page.body.count("<math ") + page.head.count("<math ") for page in pages)
        return {"pages": len(pages), "figures": figures, "notebooks": len(notebooks), "math": self.math_count,
                "examples": sum(len(r) for r in results.values()),
                "values": sum(len(v) for v in self.values.values())}

    # files
    def previous_outputs(self) -> set[str]:
        """What an earlier weave wrote into the output folder, as far as can be known: the files its
        manifest lists, and the pages and style sheet that carry the weave's mark with the figures and
        notebooks those pages link to. The second is what a folder woven before the weave kept a
        manifest holds (docs/ up to issue 32: that weave removed every other file of figures/ and
        notebooks/), and what a lost or damaged manifest leaves known. A user's own file is in
        neither, so that the weave never removes or replaces it."""
        if not self.out.is_dir():
            return set()
        found = {name for name in read_manifest(self.out, self.warn) or [] if self.removable(name)}
        pages = {name for name in ["style.css"] + sorted(p.name for p in self.out.glob("*.html"))
                 if self.removable(name)}
        for name in sorted(n for n in pages if n.endswith(".html")):
            page = (self.out / name).read_text(encoding="utf-8", errors="replace")
            found |= {link for link in map(html.unescape, OUTPUT_LINK.findall(page)) if self.removable(link)}
        return found | pages

    def foreseen_outputs(self) -> list[str]:
        """The files the weave will write whatever the examples do: pages, style sheet, notebooks."""
        stems = [Path(document.path).stem for document in self.web.documents]
        return (["index.html", "style.css"] + [stem + ".html" for stem in stems]
                + ([f"notebooks/{stem}.ipynb" for stem in stems] if self.notebooks else []))

    def removable(self, name: str) -> bool:
        """Whether the weave may remove or replace the file ``name`` of the output folder: a name the
        weave gives (``weave_like``), a plain file inside the folder (not a link), and, for a page or
        the style sheet, one that carries the weave's mark."""
        path = self.out / name
        return (weave_like(name) and path.is_file() and not path.is_symlink() and tangle.inside(self.out, path)
                and carries_mark(path, name))

    def refuse_foreign(self, names, previous: set[str]) -> None:
        """Stop, naming them, if files the weave is to write exist in the output folder and an earlier
        weave did not write them (a user's own index.html, a folder named like a page)."""
        foreign = sorted(n for n in names if n not in previous and (os.path.lexists(self.out / n)
                                                                    or not tangle.inside(self.out, self.out / n)))
        if foreign:
            raise OptionError(
                f"--out {self.out}: {len(foreign)} file(s) the weave writes exist there and were not written "
                f"by an earlier weave (not in its {MANIFEST}): {', '.join(foreign[:10])}"
                f"{' ...' if len(foreign) > 10 else ''}; move them away or weave into another folder; "
                "nothing was changed")

    def install(self) -> None:
        """Move the new files into the output folder, leave unchanged ones untouched, and remove what
        an earlier weave wrote that this one did not (``previous_outputs``); other files there
        (docs/daisy/, a user's own) stay. Each file is moved into place in one step (``os.replace``
        from the build folder beside it), and the manifest lists the old and the new files while
        they are exchanged, so that a run killed midway leaves whole files, all of them known to the
        next weave; a failure or an interrupt (Ctrl-C, SIGTERM) puts back what was there."""
        new = {p.relative_to(self.build).as_posix() for p in self.build.rglob("*") if p.is_file()}
        previous = self.previous_outputs()
        self.refuse_foreign(new, previous)
        undo: list[tuple[Path, bytes | None]] = []  # what each step replaced, in order
        folders = {folder for name in new for folder in (self.out / name).parents
                   if folder == self.out or self.out in folder.parents}
        made = sorted((f for f in folders if not f.exists()), key=lambda folder: len(folder.parts))  # outermost first
        remove_leftover_temporaries(self.out)
        current = MANIFEST
        try:
            self.replace(MANIFEST, manifest_text(previous | new), undo)
            for current in sorted(new):
                target = self.out / current
                if target.is_file() and target.read_bytes() == (self.build / current).read_bytes():
                    continue
                target.parent.mkdir(parents=True, exist_ok=True)
                undo.append((target, target.read_bytes() if target.is_file() else None))
                os.replace(self.build / current, target)
            for current in sorted(previous - new):
                undo.append((self.out / current, (self.out / current).read_bytes()))
                (self.out / current).unlink()
            current = MANIFEST
            self.replace(MANIFEST, manifest_text(new), undo)
        except BaseException as error:
            tangle.put_back(undo, made, WEAVE_TEMPORARY_SUFFIX)
            if not isinstance(error, OSError):
                raise
            raise WeaveError(f"cannot write {self.out / current} ({error.strerror or error}); "
                             f"{self.out} is left as it was") from None
        emptied = {folder for name in previous - new for folder in (self.out / name).parents
                   if self.out in folder.parents}
        for folder in sorted(emptied, key=lambda folder: -len(folder.parts)):  # the deepest first
            if folder.is_dir() and not folder.is_symlink() and not any(folder.iterdir()):
                folder.rmdir()  # emptied by this weave

    def replace(self, name: str, text: str, undo: list) -> None:
        """Write a file of the output folder in one step, remembering what it replaced."""
        path = self.out / name
        path.parent.mkdir(parents=True, exist_ok=True)
        undo.append((path, path.read_bytes() if path.is_file() else None))
        replace_bytes(path, text.encode("utf-8"))

    def write(self, name: str, text: str) -> None:
        path = self.build / name
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("w", encoding="utf-8", newline="\n") as handle:
            handle.write(text)

    def stylesheet(self) -> str:
        from pygments.formatters import HtmlFormatter

        pygments_css = HtmlFormatter(style="default").get_style_defs(".highlight")
        replaced = (".highlight {", ".highlight  {", "pre {", "td.linenos", "span.linenos")  # the page's own
        pygments_css = "\n".join(line for line in pygments_css.splitlines() if not line.startswith(replaced))
        style = STYLE_FILE.read_text(encoding="utf-8")
        return (f"/* Generated by {GENERATOR}. */\n{style}\n/* Pygments (style 'default') */\n{pygments_css}\n"
                f"{PYGMENTS_OVERRIDES}")

    # HTML pages
    def frame(self, title: str, bar: str, content: str, footer: str) -> str:
        return (
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
            f"<meta name=\"generator\" content=\"{GENERATOR}\">\n"
            f"<title>{html.escape(title)}</title>\n<link rel=\"stylesheet\" href=\"style.css\">\n</head>\n<body>\n"
            f"<div class=\"site-bar\"><nav class=\"site\">{bar}</nav></div>\n<main>\n{content}</main>\n"
            f"<footer><p>{footer}</p></footer>\n</body>\n</html>\n"
        )

    def page_html(self, page: Page, previous: Page | None, following: Page | None) -> str:
        bar = ['<a class="home" href="index.html">ident: the literate program</a>']
        if previous:
            bar.append(f'<a href="{previous.file}" rel="prev" title="{html.escape(previous.title)}">'
                       f'← <span>{html.escape(previous.title)}</span></a>')
        if following:
            bar.append(f'<a href="{following.file}" rel="next" title="{html.escape(following.title)}">'
                       f'<span>{html.escape(following.title)}</span> →</a>')
        if self.notebooks:
            bar.append(f'<a href="notebooks/{Path(page.file).stem}.ipynb" download>notebook</a>')
        toc = self.toc_html(page.headings, page.file, with_page=False)
        content = page.head + (f'<nav class="toc" aria-label="contents"><h2>Contents</h2>\n{toc}</nav>\n'
                               if toc else "") + page.body
        footer = (f"Woven from <code>{html.escape(page.document.path)}</code> by <code>weave.py</code>; "
                  "the package <code>src/ident/</code> is tangled from the same text by <code>tangle.py</code>.")
        return self.frame(page.title, " ".join(bar), content, footer)

    @staticmethod
    def toc_html(headings, file: str, with_page: bool, levels=(2, 3)) -> str:
        """Nested lists of the headings of the given levels."""
        out, depth = [], 0
        for level, anchor, label in headings:
            if level not in levels:
                continue
            wanted = min(level - min(levels) + 1, depth + 1)
            if wanted > depth:
                out.append("<ul>")
                depth = wanted
            else:
                out.append("</li>")
                while depth > wanted:
                    out.append("</ul></li>")
                    depth -= 1
            href = (file if with_page else "") + f"#{anchor}"
            out.append(f'<li><a href="{href}">{label}</a>')
        if depth:
            out.append("</li>")
            while depth > 1:
                out.append("</ul></li>")
                depth -= 1
            out.append("</ul>")
        return "\n".join(out) + ("\n" if out else "")

    def index_html(self, pages: list[Page], api: list[dict]) -> str:
        intro = pages[0].title if pages else "ident"
        parts = [f"<h1>{html.escape(intro)}</h1>",
                 pages[0].front if pages else "",
                 f'<p class="muted">This is the literate program of the Python package <code>ident</code>, '
                 "woven from the Markdown documents in <code>literate/</code>: the text with its mathematics, "
                 "the code chunks of the package with their cross references, and the examples with their "
                 f'output as they ran when this was woven. <a href="{pages[0].file if pages else "#"}">'
                 "Start reading</a>.</p>",
                 '<nav class="toc" aria-label="contents"><h2>Contents</h2>']
        part = None
        for k, page in enumerate(pages):  # under the heading of their part, numbered on across parts
            if k == 0 or self.parts[page.document.path] != part:
                part = self.parts[page.document.path]
                parts.append(("</ol>\n" if k else "") + (f'<h3 class="part">{html.escape(part)}</h3>\n' if part else "")
                             + (f'<ol start="{k + 1}">' if k else "<ol>"))
            sub = self.toc_html(page.headings, page.file, with_page=True, levels=(2,))
            notebook = (f' <span class="muted">(<a href="notebooks/{Path(page.file).stem}.ipynb" download>'
                        "notebook</a>)</span>" if self.notebooks else "")
            parts.append(f'<li><a href="{page.file}">{html.escape(page.title)}</a>{notebook}\n{sub}</li>')
        if part:
            parts.append(f'</ol>\n<h3 class="part">Indexes</h3>\n<ol start="{len(pages) + 1}">')
        parts.append('<li><a href="#chunks">Index of chunks</a></li>')
        if api:
            parts.append('<li><a href="#public-names">Index of the public names</a></li>')
        parts.append("</ol></nav>")
        parts.append(self.chunk_index_html())
        parts.append(self.api_html(api))
        bar = '<a class="home" href="index.html">ident: the literate program</a>'
        if pages:
            bar += f' <a href="{pages[0].file}">start reading →</a>'
        footer = ("Woven from <code>literate/</code> by <code>weave.py</code> "
                  "(<code>python weave.py</code>).")
        return self.frame("ident: the literate program", bar, "\n".join(parts) + "\n", footer)

    def chunk_index_html(self) -> str:
        """Noweb's index: each chunk with the numbers of its pieces and of the chunks using it."""
        xref = self.xref

        def number(piece: Piece) -> str:
            where = f"{piece.block.location}: ⟨{piece.block.name}⟩"
            return f'<a href="{piece.page}#{piece.anchor}" title="{html.escape(where)}">{piece.number}</a>'

        def entry(name: str) -> str:
            pieces = xref.by_name[name]
            text = (f'<li><span class="chunk-name">⟨<a href="{pieces[0].page}#{pieces[0].anchor}">'
                    f"{chunk_title(name)}</a>⟩</span> {', '.join(number(p) for p in pieces)}")
            if not tangle.is_root(name):
                users = xref.uses.get(name, [])
                text += (' <span class="muted">used in</span> ' + ", ".join(number(p) for p in users)
                         if users else ' <span class="muted">(not used)</span>')
            return text + "</li>"

        roots = sorted(n for n in xref.by_name if tangle.is_root(n))
        others = sorted((n for n in xref.by_name if not tangle.is_root(n)), key=lambda n: (n.casefold(), n))
        return ('<h2 id="chunks">Index of chunks</h2>\n<p>The numbers are those of the chunks in the '
                "text: first the definition and its continuations, then, after “used in”, the chunks that "
                "include it. The files of the package come first; hovering over a number shows where it "
                "is.</p>\n<h3 id=\"chunks-files\">Files</h3>\n<ul class=\"chunk-index\">\n"
                + "\n".join(entry(n) for n in roots)
                + '\n</ul>\n<h3 id="chunks-all">Chunks</h3>\n<ul class="chunk-index">\n'
                + "\n".join(entry(n) for n in others) + "\n</ul>")

    def public_names(self) -> list[dict]:
        """The names in ident.__all__ with their kind, summary and defining chunk."""
        if not (self.root / tangle.PACKAGE_DIR / "__init__.py").is_file():
            return []
        try:
            import importlib

            package = importlib.import_module("ident")
        except Exception as error:  # the index is optional; the examples would have failed first
            self.warn(f"weave: warning: cannot import ident for the index of public names: {error}")
            return []
        entries = []
        for name in getattr(package, "__all__", []):
            value = getattr(package, name, None)
            if inspect.isclass(value):
                kind = "exception" if issubclass(value, BaseException) else "class"
            elif callable(value):
                kind = "function"
            else:
                kind = "constant"
            doc = inspect.getdoc(value) if kind != "constant" else ""
            summary = (doc or "").strip().split("\n\n")[0].replace("\n", " ")
            if kind == "class" and summary.startswith(name + "("):  # a dataclass's generated docstring
                summary = ""
            module = getattr(value, "__module__", None) or package.__name__
            entries.append({"name": name, "kind": kind, "summary": summary,
                            "piece": self.defining_piece(name, module)})
        return entries

    def defining_piece(self, name: str, module: str) -> Piece | None:
        pattern = re.compile(rf"^(\s*)(?:async\s+def|def|class)\s+{re.escape(name)}\b|^({re.escape(name)})\s*[:=]")
        parts = module.split(".")
        root = "/".join([tangle.PACKAGE_DIR] + parts[1:]) + ".py" if parts[0] == "ident" else ""
        candidates = reachable(self.web, root) if root in self.web.pieces else []
        if root and root not in self.web.pieces:
            candidates = reachable(self.web, root[:-3] + "/__init__.py")
        everything = [n for n in self.xref.by_name if n not in candidates]
        for names in (candidates, everything):
            best = None
            for chunk in names:
                for piece in self.xref.by_name.get(chunk, []):
                    for line in piece.block.lines:
                        match = pattern.match(line)
                        if match and (best is None or (match[1] or "") == ""):
                            if (match[1] or "") == "":
                                return piece
                            best = best or piece
            if best:
                return best
        return None

    def api_html(self, api: list[dict]) -> str:
        if not api:
            return ""
        rows = []
        for entry in api:
            piece = entry["piece"]
            where = (f'<span class="chunk-name">⟨<a href="{piece.page}#{piece.anchor}">'
                     f'{chunk_title(piece.block.name)}</a>⟩</span>&#x2009;<span class="chunk-num">'
                     f"{piece.number}</span>") if piece else ""
            call = "()" if entry["kind"] == "function" else ""
            summary = re.sub(r"`+([^`]+)`+", r"<code>\1</code>", html.escape(entry["summary"]))
            rows.append(f'<tr><td><code>{html.escape(entry["name"])}{call}</code><br>'
                        f'<span class="muted kind">{entry["kind"]}</span></td>'
                        f"<td>{summary}</td><td>{where}</td></tr>")
        return ('<h2 id="public-names">Index of the public names</h2>\n<p>What <code>import ident</code> '
                "exports (<code>ident.__all__</code>), with the first paragraph of each docstring and the chunk "
                "that defines it.</p>\n<table class=\"api-table\">\n"
                "<tr><th>name</th><th>summary</th><th>defined in</th></tr>\n"
                + "\n".join(rows) + "\n</table>")

    # notebooks
    def write_notebook(self, document: tangle.Document, results: dict) -> str | None:
        import jupytext
        import nbformat

        try:
            notebook = jupytext.reads(self.text_with_values(document.path, marked=False)[0], fmt="md")
        except Exception as error:
            self.warn(f"{document.path}: warning: jupytext cannot read it, no notebook: {error}")
            return None
        examples = [b for b in document.items if isinstance(b, tangle.Block) and b.kind == "example"]
        cells = [c for c in notebook.cells if c.cell_type == "code"]
        expected = ["\n".join(["# example: " + b.name] + b.lines) for b in examples]
        if [c.source for c in cells] != expected:
            self.warn(f"{document.path}: warning: the notebook's code cells are not the examples; "
                      "the notebook is written without outputs")
            examples = []
        for count, (cell, block) in enumerate(zip(cells, examples), start=1):
            result = results[block.location]
            cell.execution_count = count
            cell.outputs = self.notebook_outputs(result)
        for k, cell in enumerate(notebook.cells):
            cell.id = f"cell-{k + 1}"
            cell.metadata = {}
        notebook.metadata = {
            "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
            "language_info": {"name": "python"},
        }
        nbformat.validate(notebook)
        name = f"notebooks/{Path(document.path).stem}.ipynb"
        self.write(name, nbformat.writes(notebook) + "\n")
        return name

    def notebook_outputs(self, result: Result) -> list:
        import nbformat

        outputs = []
        for stream, text in (("stdout", result.stdout), ("stderr", result.stderr)):
            if text:
                outputs.append(nbformat.v4.new_output("stream", name=stream, text=text))
        for figure in result.figures:
            suffix = Path(figure.path).suffix.lower()
            data = (self.build / figure.path).read_bytes()
            if suffix == ".svg":
                bundle = {"image/svg+xml": data.decode("utf-8")}
            elif suffix in MIME:
                bundle = {MIME[suffix]: base64.b64encode(data).decode("ascii")}
            else:
                continue
            bundle["text/plain"] = f"<Figure {Path(figure.path).name}>"
            outputs.append(nbformat.v4.new_output("display_data", data=bundle))
        return outputs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python weave.py", description=__doc__.split("\n\n")[0])
    default_root = Path(__file__).resolve().parent
    parser.add_argument("--root", type=Path, default=default_root,
                        help="project root holding literate/ (default: this file's folder)")
    parser.add_argument("--out", type=Path, help="output folder (default: ROOT/docs)")
    parser.add_argument("--no-notebooks", action="store_true", help="write the pages only")
    args = parser.parse_args(argv)
    out = args.out if args.out is not None else args.root / "docs"
    try:
        check_options(args.root, out)
        weave = Weave(args.root, out, notebooks=not args.no_notebooks)
        with tangle.interrupt_on_sigterm():
            summary = weave.run()
    except OptionError as error:
        print(f"weave: error: {error}", file=sys.stderr)
        return 2
    except (tangle.TangleError, WeaveError) as error:
        print(f"weave: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"weave: interrupted; {out} is left as it was", file=sys.stderr)
        return 130
    except OSError as error:  # the output folder cannot be written (permissions, a full disk)
        print(f"weave: error: {error.filename or out}: {error.strerror or error}", file=sys.stderr)
        return 1
    except ImportError as error:
        print(f"weave: error: {error}; install the documentation dependencies: pip install -e '.[docs]'",
              file=sys.stderr)
        return 1
    print(f"weave: wrote {out}: {summary['pages']} pages and index.html, {summary['examples']} examples run, "
          f"{summary['values']} inline values, {summary['figures']} figures, {summary['notebooks']} notebooks, "
          f"{summary['math']} formulas "
          f"in {summary['seconds']:.1f} s")
    return 0


def check_options(root: Path, out: Path) -> None:
    """--root must hold literate/ and --out must be a folder or not exist, before anything runs."""
    try:
        tangle.check_root(root)
    except tangle.TangleError as error:
        raise OptionError(str(error)) from None
    if os.path.lexists(out) and not out.is_dir():
        raise OptionError(f"--out {out} exists and is not a folder; name a folder (it is made if missing)")
    blocking = next((p for p in out.absolute().parents if os.path.lexists(p) and not p.is_dir()), None)
    if blocking is not None:
        raise OptionError(f"--out {out}: {blocking} is a file, not a folder; name a folder")


if __name__ == "__main__":
    sys.exit(main())
