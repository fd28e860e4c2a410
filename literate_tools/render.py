"""The renderer: one literate document to one HTML page (markdown-it), with highlighted chunks and
their links, examples with their output and figures, inline values, and the apparatus of a paper
(parts, numbered formulas, figures and tables, citations, links between the documents).

The syntax of the apparatus is in README.md, "The woven document".  Labels are collected from every
page (``PageRenderer.prepare``) before any page is rendered (``PageRenderer.render``), so that a
reference may point forward or to another page.
"""
from __future__ import annotations

import dataclasses
import html
import os
import re
from pathlib import Path

from literate_tools import chunks
from literate_tools.examples import Figure
from literate_tools.mathml import to_mathml
from literate_tools.xref import Piece, page_name


# Pygments wraps every token in a span; names and punctuation have no rule in the default style, and
# whitespace shows no colour, so their spans only add bytes (a third of the pages' size): unwrapped.
# Operators (= . + ...) are the commonest token after names: the default style's dark grey for them
# (#666) is barely told from the text, and their spans were another eighth of the pages: unwrapped too,
# so they take the text's colour.
UNSTYLED_TOKEN = re.compile(r'<span class="(?:n|p|w|o)">([^<]*)</span>')
STRING_PART = re.compile(r'<span class="(?:sa|si|s1|se)">')  # drawn as strings (s2): one span per string
SAME_CLASS_SEAM = re.compile(r'(<span class="([a-z0-9]+)">[^<]*)</span><span class="\2">')
IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".gif", ".svg", ".webp"}
TEXT_COLUMNS = 88  # characters of code that fit in the text column (45rem in site.css)
TEXT_WIDTH_PX = 720  # the text column in CSS pixels; a wider figure widens its example
FRONT_SECTIONS = {"quick-start"}  # sections that belong to the front matter the index shows
CAPTION = re.compile(r"^\s*#\s*caption:\s*(?P<caption>\S.*?)\s*$")  # in an example: its figure's caption
PLACEHOLDER = "WEAVEREF{}X"
BLOCK_PLACEHOLDER = "WEAVEVALUE{}X"
PLACEHOLDER_HTML = re.compile(r'<span class="[^"]*">WEAVEREF(\d+)X</span>|WEAVEREF(\d+)X')


class WeaveError(Exception):
    """The weave cannot go on; the message names the literate ``file:line``."""


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


def part_marker(document: chunks.Document) -> tuple[int, str] | None:
    """(line, title) of the part a document opens: its first non-blank line ``<!-- part: TITLE -->``."""
    for number, line in document.text_lines():
        if line.strip():
            match = PART_MARKER.match(line.strip())
            return (number, match["title"]) if match else None
    return None


def figure_captions(block: chunks.Block) -> list[tuple[int, str, str | None]]:
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

    def __init__(self, weave: "site.Weave", document: chunks.Document, results: dict):
        from pygments.formatters import HtmlFormatter

        self.weave = weave
        self.document = document
        self.page = page_name(document.path)
        self.results = results
        self.formatter = HtmlFormatter(nowrap=True)
        self.blocks = {b.location.line: b for b in document.items if isinstance(b, chunks.Block)}
        self.rendered: set[int] = set()
        self.figures: dict[chunks.Location, list] = {}  # example -> (number, anchor, caption) per figure
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
            language = chunks.parse_info(token.info)[0] or "text"
            return self.highlight_block(token.content.rstrip("\n").split("\n"), language)
        self.rendered.add(line)
        if block.kind == "chunk":
            return self.render_chunk(block)
        if block.kind == "example":
            return self.render_example(block)
        return self.highlight_block(block.lines, chunks.parse_info(block.info)[0] or "text")

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
        code = STRING_PART.sub('<span class="s2">', UNSTYLED_TOKEN.sub(r"\1", highlight(text, lexer, self.formatter)))
        while (merged := SAME_CLASS_SEAM.sub(r"\1", code)) != code:  # adjacent spans of one class: one span
            code = merged
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

    def render_chunk(self, block: chunks.Block) -> str:
        xref = self.weave.xref
        piece = xref.pieces[block.location]
        names, lines = [], []
        for line in trim_blank(block.lines):
            match = chunks.REFERENCE.match(line)
            if match:
                names.append(chunks.normalise_name(match["name"]))
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
        if chunks.is_root(name):
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

    def render_example(self, block: chunks.Block) -> str:
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
    return f"<code>{html.escape(name)}</code>" if chunks.is_root(name) else html.escape(name)


def plain_title(inline) -> str:
    """A heading as plain text (for <title> and the navigation): formulas as their LaTeX source."""
    return "".join(child.content for child in inline.children or []
                   if child.type in ("text", "code_inline", "math_inline")).strip()


@dataclasses.dataclass
class Page:
    document: chunks.Document
    file: str
    title: str
    headings: list[tuple[int, str, str]]  # level, id, label (HTML)
    head: str  # the HTML up to and including the title
    body: str
    front: str = ""  # the HTML between the title and the first section (a quick start counts as front)
