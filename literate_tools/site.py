"""Weave the literate sources of ident (``literate/*.md``) into a browsable document in ``docs/``.

``python weave.py`` writes, from the documents that ``tangle.py``
reads:

* one HTML page per literate document and ``index.html`` with the contents, an index of the
  chunks and an index of the package's public names (``ident.__all__``);
* ``style.css``: the page style (``literate_tools/site.css``, read when weaving) and the Pygments
  highlighting classes;
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
import contextlib
import html
import inspect
import json
import os
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

from literate_tools import chunks, tangle
from literate_tools.examples import DocumentRun, ExampleRunner, Result, example_environment
from literate_tools.render import (BLOCK_PLACEHOLDER, PART_MARKER, Apparatus, Page, PageRenderer, WeaveError,
                                   chunk_title, part_marker)
from literate_tools.xref import Piece, cross_references, reachable


GENERATOR = "ident weave.py"
MIME = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".gif": "image/gif",
        ".svg": "image/svg+xml", ".webp": "image/webp"}


class OptionError(WeaveError):
    """A bad ``--root`` or ``--out`` (the command line exits 2); the message names the option."""


# --------------------------------------------------------------------------------------------
# The whole weave


STYLE_FILE = Path(__file__).resolve().with_name("site.css")  # the page style, read when weaving


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
        self.texts = {relative: chunks.read_literate(path, relative).removeprefix("\ufeff")
                      for path in chunks.literate_files(self.root)
                      for relative in [path.relative_to(self.root).as_posix()]}
        self.web = chunks.build_web([chunks.parse_document(text, path) for path, text in self.texts.items()])
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
            expression = chunks.INLINE_VALUE.match(lines[line - 1], start)["expression"].strip()
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
                          if isinstance(unit, chunks.Block)} for path, run in runs.items()}
        self.values = {path: {(unit.location.line, unit.start, unit.end): outcome.value
                              for unit, outcome in zip(run.units, run.outcomes)
                              if isinstance(unit, chunks.InlineValue)} for path, run in runs.items()}
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
            if not chunks.is_root(name):
                users = xref.uses.get(name, [])
                text += (' <span class="muted">used in</span> ' + ", ".join(number(p) for p in users)
                         if users else ' <span class="muted">(not used)</span>')
            return text + "</li>"

        roots = sorted(n for n in xref.by_name if chunks.is_root(n))
        others = sorted((n for n in xref.by_name if not chunks.is_root(n)), key=lambda n: (n.casefold(), n))
        return ('<h2 id="chunks">Index of chunks</h2>\n<p>The numbers are those of the chunks in the '
                "text: first the definition and its continuations, then, after “used in”, the chunks that "
                "include it. The files of the package come first; hovering over a number shows where it "
                "is.</p>\n<h3 id=\"chunks-files\">Files</h3>\n<ul class=\"chunk-index\">\n"
                + "\n".join(entry(n) for n in roots)
                + '\n</ul>\n<h3 id="chunks-all">Chunks</h3>\n<ul class="chunk-index">\n'
                + "\n".join(entry(n) for n in others) + "\n</ul>")

    def public_names(self) -> list[dict]:
        """The names in ident.__all__ with their kind, summary and defining chunk."""
        if not (self.root / chunks.PACKAGE_DIR / "__init__.py").is_file():
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
        root = "/".join([chunks.PACKAGE_DIR] + parts[1:]) + ".py" if parts[0] == "ident" else ""
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
    def write_notebook(self, document: chunks.Document, results: dict) -> str | None:
        import jupytext
        import nbformat

        try:
            notebook = jupytext.reads(without_package_code(self.text_with_values(document.path, marked=False)[0]),
                                      fmt="md")
        except Exception as error:
            self.warn(f"{document.path}: warning: jupytext cannot read it, no notebook: {error}")
            return None
        examples = [b for b in document.items if isinstance(b, chunks.Block) and b.kind == "example"]
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
        """The example's printed text, and each figure as a link to its file in the woven folder
        (``../figures/...`` from ``notebooks/``): the figures are on disk once, not again inside every
        notebook as base64 (which would double their weight in the woven document)."""
        import nbformat

        outputs = []
        for stream, text in (("stdout", result.stdout), ("stderr", result.stderr)):
            if text:
                outputs.append(nbformat.v4.new_output("stream", name=stream, text=text))
        for figure in result.figures:
            if Path(figure.path).suffix.lower() not in MIME:
                continue
            name = Path(figure.path).name
            outputs.append(nbformat.v4.new_output("display_data", data={
                "text/markdown": f"![{name}](../{figure.path})", "text/plain": f"<Figure {name}>"}))
        return outputs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python weave.py", description=__doc__.split("\n\n")[0])
    default_root = Path(__file__).resolve().parents[1]  # the project root: literate_tools/ is in it
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
    except (chunks.TangleError, WeaveError) as error:
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
        chunks.check_root(root)
    except chunks.TangleError as error:
        raise OptionError(str(error)) from None
    if os.path.lexists(out) and not out.is_dir():
        raise OptionError(f"--out {out} exists and is not a folder; name a folder (it is made if missing)")
    blocking = next((p for p in out.absolute().parents if os.path.lexists(p) and not p.is_dir()), None)
    if blocking is not None:
        raise OptionError(f"--out {out}: {blocking} is a file, not a folder; name a folder")


def without_package_code(text: str) -> str:
    """The text with the body of each package chunk replaced by one line saying where the code is. A
    notebook is for running the examples; the package's code is on the woven page and in src/ident,
    and in the notebooks it was half of the bytes of docs/."""
    lines, kept, k = text.split("\n"), [], 0
    while k < len(lines):
        kept.append(lines[k])
        fence = chunks.FENCE.match(lines[k])
        header = chunks.CHUNK_HEADER.match(lines[k + 1]) if fence and k + 1 < len(lines) else None
        if not header:
            k += 1
            continue
        end = next((j for j in range(k + 2, len(lines)) if lines[j].startswith(fence["fence"])), len(lines))
        kept += [lines[k + 1], f"# ... {end - k - 2} lines of the package: on the woven page, and tangled into "
                               "src/ident"]
        k = end
    return "\n".join(kept)
