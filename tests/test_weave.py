"""The weave (``python weave.py``): pages, cross references, mathematics, examples with their
output and figures, notebooks, failures that name the literate line, and a weave that gives the same
files twice apart from measured times.

The small literate project below exercises each feature; the real ``literate/`` is woven twice in
subprocesses for the determinism test and the checks of the whole document.
"""
from __future__ import annotations

import html.parser
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

import tangle
from conftest import PROJECT_ROOT

weave = pytest.importorskip("weave")
pytest.importorskip("latex2mathml", reason="the weave needs latex2mathml (the docs extra)")


FIRST = '''\
# A small program with $x^2$

Some text with inline math $a_1 + \\hat w$ and a display:

$$
\\min_{\\hat w} \\lVert w - \\hat w \\rVert^2
$$

| a | b |
|---|---|
| 1 | $\\ell$ |

See [the second document](02-second.md) too.

## The code

```python .noeval
# <<src/ident/mini.py>>=
"""Generated."""
<<helper>>
```

The helper:

```python .noeval
# <<helper>>=
def helper():
    return "<<not a reference>>"
```

## Examples

```python
# example: prints and plots
import matplotlib.pyplot as plt

print("hello <world> & all")
# caption: A line through *three* points, $x^2$ aside.
plt.figure(figsize=(2, 2))
plt.plot([1, 2, 3])
shared = 41
```

```python
# example: writes its own figure
import os
from pathlib import Path

from matplotlib.figure import Figure

own = Figure(figsize=(2, 2))
own.subplots().plot([3, 2, 1])
own.savefig(Path(os.environ["IDENT_FIGURES"]) / "own-figure.png")
print("the figure folder is", os.environ["IDENT_FIGURES"])
```

```python
# example: binds a figure and uses the namespace
from matplotlib.figure import Figure

bound = Figure(figsize=(2, 2))
bound.subplots().plot([1, 1])
print(shared + 1)
```
'''

SECOND = '''\
# The second document

```python .noeval
# <<helper>>+=
HELPER_CONSTANT = 2
```

```sh
echo display only
```

```python
# example: a fresh namespace per document
print("shared" in globals())
```
'''


def make_project(root: Path, first: str = FIRST, second: str = SECOND) -> Path:
    (root / "literate").mkdir(parents=True)
    (root / "literate" / "01-first.md").write_text(first, encoding="utf-8")
    (root / "literate" / "02-second.md").write_text(second, encoding="utf-8")
    outputs, _ = tangle.tangle(root)
    tangle.write(root, outputs)
    return root


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> tuple[Path, Path, dict]:
    root = make_project(tmp_path_factory.mktemp("project"))
    out = root / "docs"
    out.mkdir()
    (out / "README.md").write_text("kept\n")
    (out / "figures").mkdir()
    (out / "figures" / "stale.png").write_bytes(b"old")  # an earlier weave's, as its manifest says
    (out / "figures" / "mine.png").write_bytes(b"user")  # the user's own
    (out / weave.MANIFEST).write_text(weave.manifest_text(["figures/stale.png"]), encoding="utf-8")
    summary = weave.Weave(root, out).run()
    return root, out, summary


def read(out: Path, name: str) -> str:
    return (out / name).read_text(encoding="utf-8")


class Links(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.ids, self.hrefs, self.images = [], [], []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if "id" in attrs:
            self.ids.append(attrs["id"])
        if tag == "a" and attrs.get("href"):
            self.hrefs.append(attrs["href"])
        if tag == "img":
            self.images.append(attrs.get("src"))


def parse(text: str) -> Links:
    links = Links()
    links.feed(text)
    return links


def check_links(out: Path, root: Path | None = None) -> None:
    """Every relative link leads to a file, and every #anchor to an id of its page (links to the
    repository's files from the docs/ of root, where given)."""
    pages = {p.name: parse(read(out, p.name)) for p in out.glob("*.html")}
    for name, links in pages.items():
        assert len(links.ids) == len(set(links.ids)), f"{name}: duplicate ids"
        for href in links.hrefs:
            if re.match(r"^[a-z]+:", href):
                continue
            target, _, anchor = href.partition("#")
            target = target or name
            # a repository file (../reference/...) or the runner's daisy/ is linked from the repository's
            # docs/, where the pages live; every other target is written by the weave
            base = root / "docs" if root is not None and target.startswith(("../", "daisy/")) else out
            assert (base / target).is_file(), f"{name}: link to a missing file {href}"
            if anchor:
                assert anchor in pages[target].ids, f"{name}: link to a missing anchor {href}"
        for source in links.images:
            assert (out / source).is_file(), f"{name}: missing image {source}"


# --------------------------------------------------------------------------------------------
# the small project


def test_pages_index_and_style_are_written(small) -> None:
    root, out, summary = small
    assert {p.name for p in out.glob("*.html")} == {"01-first.html", "02-second.html", "index.html"}
    assert (out / "style.css").is_file() and ".highlight" in read(out, "style.css")
    assert read(out, "README.md") == "kept\n"  # not written by the weave: left alone
    assert not (out / "figures" / "stale.png").exists()  # an earlier weave's figure is removed
    assert (out / "figures" / "mine.png").read_bytes() == b"user"  # a file no weave wrote stays
    assert summary["pages"] == 2 and summary["examples"] == 4 and summary["values"] == 0


def test_chunks_are_named_and_cross_referenced(small) -> None:
    _, out, _ = small
    first, second = read(out, "01-first.html"), read(out, "02-second.html")
    assert "⟨<code>src/ident/mini.py</code>⟩</span><span class=\"chunk-op\">≡" in first
    assert "⟨helper⟩</span><span class=\"chunk-op\">≡" in first
    assert "⟨helper⟩</span><span class=\"chunk-op\">+≡" in second
    # the reference in the root chunk links to the definition of <<helper>>
    assert '⟨<a href="#chunk-helper">helper</a>' in first
    # the definition says where it is used and continued, the continuation where it is defined
    definition = first[first.index('id="chunk-helper"'):]
    assert 'Used in <a href="#chunk-src-ident-mini-py">' in definition
    assert 'Continued in <a href="02-second.html#chunk-helper-2">' in definition
    assert 'Defined in <a href="01-first.html#chunk-helper">' in second
    assert "Root chunk: written to <code>src/ident/mini.py</code>" in first
    # a string that looks like a reference is code, not a link
    assert "&lt;&lt;not a reference&gt;&gt;" in first
    check_links(out)


def test_code_is_highlighted(small) -> None:
    _, out, _ = small
    first, second = read(out, "01-first.html"), read(out, "02-second.html")
    assert '<span class="k">def</span>' in first
    assert '<span class="nb">echo</span>' in second  # the sh display block, with its own lexer


def test_headings_get_ids_and_a_table_of_contents(small) -> None:
    _, out, _ = small
    first = read(out, "01-first.html")
    assert '<h2 id="the-code">' in first and '<a href="#the-code">The code</a>' in first
    assert "<title>A small program with x^2</title>" in first
    index = read(out, "index.html")
    assert '<a href="01-first.html#the-code">' in index and 'href="02-second.html"' in index


def test_mathematics_becomes_mathml(small) -> None:
    _, out, _ = small
    first = read(out, "01-first.html")
    assert first.count("<math ") == 5  # title, inline, display, table cell, a caption
    assert '<math xmlns="http://www.w3.org/1998/Math/MathML" display="block">' in first
    assert "$" not in re.sub(r"<pre.*?</pre>", "", first, flags=re.S)
    assert "<table>" in first
    assert "<script" not in first


def test_links_to_literate_documents_lead_to_their_pages(small) -> None:
    _, out, _ = small
    assert '<a href="02-second.html">the second document</a>' in read(out, "01-first.html")


def test_examples_show_their_output_and_figures(small) -> None:
    _, out, _ = small
    first, second = read(out, "01-first.html"), read(out, "02-second.html")
    assert "hello &lt;world&gt; &amp; all" in first
    assert ">42</pre>" in first  # the examples of a document share a namespace
    assert ">False</pre>" in second  # ... and each document has its own
    assert "the figure folder is docs/figures" in first  # paths printed by examples are stable
    figures = sorted(p.name for p in (out / "figures").iterdir() if p.name != "mine.png")  # the user's own
    assert figures == ["01-first-binds-a-figure-and-uses-the-namespace.png", "01-first-prints-and-plots.png",
                       "own-figure.png"]
    for name in figures:
        assert f'src="figures/{name}"' in first
        data = (out / "figures" / name).read_bytes()
        assert data.startswith(b"\x89PNG") and b"tEXt" not in data and b"tIME" not in data
    assert 'width="220" height="220"' in first  # 2 x 2 inches at the weave's 110 dpi
    assert "own-figure.png" in first.split('id="example-writes-its-own-figure"')[1].split('class="example"')[0]


def test_figures_are_numbered_and_captioned(small) -> None:
    _, out, _ = small
    first = read(out, "01-first.html")
    assert ('<figcaption><span class="figure-number">Figure 1.</span> A line through <em>three</em> points, '
            '<math') in first
    assert 'alt="A line through three points' in first
    # figures without a caption line are numbered on and captioned with their example's name
    assert '<span class="figure-number">Figure 3.</span> binds a figure and uses the namespace' in first
    assert "Figure 1 of the example" not in first
    assert "# caption:" not in first  # the caption line is shown as the caption, not in the code


def test_the_index_opens_with_the_first_documents_abstract(small) -> None:
    _, out, _ = small
    index = read(out, "index.html")
    assert "<h1>A small program with x^2</h1>" in index
    assert index.index("Some text with inline math") < index.index('<nav class="toc"')


def test_notebooks_carry_the_outputs(small) -> None:
    nbformat = pytest.importorskip("nbformat")
    _, out, _ = small
    notebook = nbformat.read(out / "notebooks" / "01-first.ipynb", as_version=4)
    nbformat.validate(notebook)
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    assert [cell.execution_count for cell in code] == [1, 2, 3]
    assert code[0].outputs[0]["text"] == "hello <world> & all\n"
    figure = code[0].outputs[1]["data"]  # a link to the figure's file beside the notebooks, not its bytes again
    assert "image/png" not in figure and figure["text/markdown"].startswith("![") and "](../figures/" in figure["text/markdown"]
    linked = figure["text/markdown"].split("](../", 1)[1].rstrip(")")
    assert (out / linked).is_file()
    assert [cell.id for cell in notebook.cells] == [f"cell-{k}" for k in range(1, len(notebook.cells) + 1)]
    assert notebook.metadata["kernelspec"]["name"] == "python3"


def snapshot(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def test_a_failing_example_stops_the_weave_and_leaves_the_output_as_it_was(tmp_path, capsys) -> None:
    out = tmp_path / "out"
    root = make_project(tmp_path / "project")
    assert weave.main(["--root", str(root), "--out", str(out)]) == 0
    (out / "README.md").write_text("kept\n")
    before = snapshot(out)
    broken = FIRST.replace('print(shared + 1)', 'print(shared + 1)\nraise ValueError("boom")')
    (root / "literate" / "01-first.md").write_text(broken, encoding="utf-8")
    line = broken.splitlines().index('raise ValueError("boom")') + 1
    capsys.readouterr()
    status = weave.main(["--root", str(root), "--out", str(out)])
    error = capsys.readouterr().err
    assert status == 1
    assert "literate/01-first.md:" in error and "example 'binds a figure and uses the namespace' failed" in error
    assert f'literate/01-first.md", line {line}' in error
    assert "ValueError: boom" in error and "docs/ is left as it was" in error
    assert snapshot(out) == before  # byte for byte, nothing added or removed
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out-weave-")]  # no build folder left


DEPENDENT = '''\
# Dependent examples

```python
# example: defines a and fails
a = 1
b = 2
raise RuntimeError("after a and b, before c")
c = 3
```

The value of a is `{python} a + 1`, of c `{python} c`.

```python
# example: uses a only
print(a + b)
```

```python
# example: uses c
d = c + 1
```

```python
# example: uses d, skipped in turn
print(d)
```

```python
# example: independent
print("still runs")
```
'''


def test_one_failure_is_one_failure_and_its_dependents_are_skipped(tmp_path) -> None:
    root = make_project(tmp_path / "project", second=DEPENDENT)
    document = next(d for d in tangle.read_web(root).documents if d.path.endswith("02-second.md"))
    run = weave.DocumentRun(document, weave.ExampleRunner(root, None))
    outcomes = run.run_all()
    assert [o.status for o in outcomes] == ["failed", "ok", "skipped", "ok", "skipped", "skipped", "ok"]
    assert outcomes[1].value == "2"  # what ran before the failing line stands
    assert "reads c, which example 'defines a and fails' (literate/02-second.md:3) did not define" \
        in outcomes[2].message
    assert ("reads d, which example 'uses c' (literate/02-second.md:18), skipped because of example "
            "'defines a and fails' (literate/02-second.md:3), did not define") in outcomes[5].message
    assert outcomes[6].result.stdout == "still runs\n"
    problems = run.problems()
    assert len(problems) == 4 and problems[0].startswith("literate/02-second.md:3: example 'defines a and fails'")
    assert "literate/02-second.md:11: inline value `{python} c` skipped" in problems[1]


def test_inline_values_are_computed_in_reading_order(tmp_path) -> None:
    text = FIRST.replace("## Examples", "## Examples\n\nBefore: `{python} 'shared' in globals()`; the "
                         "width of the figure below: `{python} own.get_figwidth()`.") + (
        "\nAfter: shared is `{python} shared`, twice `{python} f\"{2 * shared:.1f}\"`.\n")
    root = make_project(tmp_path / "project", first=text)
    out = tmp_path / "out"
    assert weave.main(["--root", str(root), "--out", str(out)]) == 0
    page = read(out, "01-first.html")
    assert 'Before: <span class="computed" title="&#x27;shared&#x27; in globals()">False</span>;' in page
    assert '<span class="computed" title="shared">41</span>' in page
    assert '>82.0</span>' in page and "{python}" not in page
    assert 'title="own.get_figwidth()">2.0</span>' in page  # run after the example that binds `own`
    document = tangle.read_web(root).documents[0]
    order = [getattr(u, "name", None) or u.expression for u in weave.run_order(document)]
    assert order.index("own.get_figwidth()") == order.index("writes its own figure") + 1
    notebook = read(out, "notebooks/01-first.ipynb")
    assert "After: shared is 41, twice 82.0." in notebook


def test_a_value_of_several_lines_is_markdown_of_its_own(tmp_path, capsys) -> None:
    table = "\n\n`{python} '| a | b |\\n|---|---|\\n| 1 | $x^2$ |'`\n\nAfter the table.\n"
    root = make_project(tmp_path / "project", first=FIRST + table)
    out = tmp_path / "out"
    assert weave.main(["--root", str(root), "--out", str(out)]) == 0
    page = read(out, "01-first.html")
    assert '<div class="computed" title="&#x27;| a | b |' in page and "<table>" in page.split("After the table")[0]
    assert "<td>1</td>" in page and page.count("<math ") == 6  # the formula in the table is MathML too
    cells = json.loads(read(out, "notebooks/01-first.ipynb"))["cells"]
    markdown = "".join("".join(cell["source"]) for cell in cells if cell["cell_type"] == "markdown")
    assert "| a | b |\n|---|---|\n| 1 | $x^2$ |\n\nAfter the table." in markdown  # the table, as on the page
    assert "{python}" not in markdown
    inline = FIRST + "\nIn a sentence: `{python} 'two\\nlines'`.\n"
    (root / "literate" / "01-first.md").write_text(inline, encoding="utf-8")
    assert weave.main(["--root", str(root), "--out", str(out)]) == 1
    assert "must stand alone on its line" in capsys.readouterr().err


def test_a_failing_inline_value_is_reported_with_its_line(tmp_path, capsys) -> None:
    root = make_project(tmp_path / "project", first=FIRST + "\nA value: `{python} undefined_name`.\n")
    line = (FIRST + "\nA value: `{python} undefined_name`.\n").splitlines().index("A value: `{python} undefined_name`.") + 1
    assert weave.main(["--root", str(root), "--out", str(tmp_path / "out")]) == 1
    error = capsys.readouterr().err
    assert f"literate/01-first.md:{line}: inline value `{{python}} undefined_name` failed" in error
    assert "NameError" in error and not (tmp_path / "out").exists()


def test_names_an_example_reads_and_binds() -> None:
    bound, needed = weave.module_names("import numpy as np\nx = np.ones(3) + y\nfor k in range(3):\n"
                                       "    z = k\ndef f(a):\n    return a + g\n")
    assert bound == {"np", "x", "k", "z", "f"} and needed == {"y", "g"}
    assert weave.module_names("x = x + 1") == ({"x"}, {"x"})
    assert weave.module_names("f'{info.M:.3g}'", "eval") == (set(), {"info"})
    assert weave.module_names("a = 1\nb = 2\nc = 3", after=2)[0] == {"b", "c"}


def test_a_document_that_is_not_utf8_is_refused_with_its_line(tmp_path, capsys) -> None:
    root = make_project(tmp_path / "project")
    (root / "literate" / "02-second.md").write_bytes(SECOND.encode("utf-8") + b"\ncaf\xe9\n")
    assert weave.main(["--root", str(root), "--out", str(tmp_path / "out")]) == 1
    assert "literate/02-second.md:" in capsys.readouterr().err and not (tmp_path / "out").exists()


def test_unknown_latex_is_reported_with_its_line(tmp_path, capsys) -> None:
    root = make_project(tmp_path / "project", first=FIRST.replace("$a_1 + \\hat w$", "$\\nosuchmacro{x}$"))
    assert weave.main(["--root", str(root), "--out", str(tmp_path / "out")]) == 0
    assert "literate/01-first.md:3: warning: cannot convert $\\nosuchmacro{x}$" in capsys.readouterr().err
    assert '<code class="math-error">\\nosuchmacro{x}</code>' in read(tmp_path / "out", "01-first.html")


def test_mathml_is_set_as_tex_would() -> None:
    display = weave.to_mathml(r"\min_{\hat w} \lVert w - \hat w \rVert^2", display=True)
    assert '<munder><mo movablelimits="true">min</mo>' in display
    assert display.count('<mo stretchy="false">‖</mo>') == 2
    matrix = weave.to_mathml(r"\begin{bmatrix} a & b \end{bmatrix}", display=True)
    assert "<mo>[</mo>" in matrix  # brackets around a matrix still stretch
    assert weave.to_mathml(r"\Gamma \gamma", display=False).count('mathvariant="normal"') == 1


def test_a_font_command_takes_one_token_unbraced_as_tex_does() -> None:
    """\\mathcal K is \\mathcal{K}: a script K.  Browsers (MathML Core) honour mathvariant="normal" only,
    so the other fonts are set in Unicode's mathematical letters (latex2mathml gave \\mathcal K as a
    plain K with mathvariant="script", and \\mathrm{d} as an italic d)."""
    def tokens(latex: str) -> list[str]:
        return re.findall(r"<m[ino][^>]*>[^<]*</m[ino]>", weave.to_mathml(latex, display=False))

    for unbraced, braced, expected in [
            (r"\mathcal K_2", r"\mathcal{K}_2", ["<mi>𝒦</mi>", "<mn>2</mn>"]),
            (r"\mathbb R^n", r"\mathbb{R}^n", ["<mi>ℝ</mi>", "<mi>n</mi>"]),
            (r"\mathrm d x", r"\mathrm{d}x", ['<mi mathvariant="normal">d</mi>', "<mi>x</mi>"]),
            (r"A^\mathrm T", r"A^{\mathrm{T}}", ["<mi>A</mi>", '<mi mathvariant="normal">T</mi>']),
            (r"\mathbf x", r"\mathbf{x}", ["<mi>𝐱</mi>"]),
            (r"\mathbf 1", r"\mathbf{1}", ["<mn>𝟏</mn>"]),
            (r"\boldsymbol x", r"\boldsymbol{x}", ["<mi>𝒙</mi>"]),
            (r"\mathfrak g \mathit h", r"\mathfrak{g} \mathit{h}", ["<mi>𝔤</mi>", "<mi>ℎ</mi>"])]:
        assert tokens(unbraced) == tokens(braced) == expected, unbraced
    assert tokens(r"\mathcal KL") == ["<mi>𝒦</mi>", "<mi>L</mi>"]  # one token, as in TeX
    assert tokens(r"\mathcal{KL}") == ["<mi>𝒦</mi>", "<mi>ℒ</mi>"]



def test_png_metadata_is_removed() -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    import io

    buffer = io.BytesIO()
    Figure(figsize=(1, 1)).savefig(buffer, format="png", metadata={"Software": "x", "Title": "t"})
    data = buffer.getvalue()
    assert b"tEXt" in data
    stripped = weave.strip_png_metadata(data)
    assert b"tEXt" not in stripped and stripped.startswith(b"\x89PNG") and stripped.endswith(data[-12:])
    assert weave.png_size(stripped) == weave.png_size(data) == (100, 100)


# --------------------------------------------------------------------------------------------
# the real literate/


def weave_real(out: Path) -> subprocess.CompletedProcess:
    """Weave the real document; skip (not fail) when examples failed: tests/test_examples.py reports
    each of them once, as its own failure."""
    done = subprocess.run([sys.executable, "weave.py", "--out", str(out)], cwd=PROJECT_ROOT,
                          capture_output=True, text=True, timeout=900)
    if done.returncode != 0 and "did not run; docs/ is left as it was" in done.stderr:
        pytest.skip("the weave stopped because examples failed (see tests/test_examples.py): "
                    + done.stderr.splitlines()[1][:300])
    assert done.returncode == 0, f"the weave failed:\n{done.stdout}\n{done.stderr}"
    return done


def sources() -> dict[str, bytes]:
    """The literate documents and the generated package, as the weave reads them."""
    files = list((PROJECT_ROOT / "literate").rglob("*.md")) + list((PROJECT_ROOT / "src").rglob("*.py"))
    return {p.relative_to(PROJECT_ROOT).as_posix(): p.read_bytes() for p in files}


REAL_SOURCES: dict[str, bytes] = {}


@pytest.fixture(scope="module")
def real(tmp_path_factory) -> Path:
    REAL_SOURCES.update(sources())
    out = tmp_path_factory.mktemp("real-a")
    weave_real(out)
    return out




def test_weave_is_deterministic(real, tmp_path) -> None:
    """Two weaves of the same sources write the same bytes: no times, dates or machine names in the
    output, so that the main job leaves a clean checkout clean."""
    again = tmp_path / "real-b"
    weave_real(again)
    if sources() != REAL_SOURCES:  # someone edited literate/ meanwhile (a shared working tree)
        pytest.skip("literate/ or src/ changed between the two weaves; run the test again")
    files = sorted(p.relative_to(real).as_posix() for p in real.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(again).as_posix() for p in again.rglob("*") if p.is_file())
    for name in files:
        assert (real / name).read_bytes() == (again / name).read_bytes(), f"{name} differs between two weaves"


def test_the_real_document(real) -> None:
    documents = [tangle.parse_document(text.decode("utf-8"), path) for path, text in sorted(REAL_SOURCES.items())
                 if path.startswith("literate/")]  # what the weave read, even if literate/ changed since
    web = tangle.build_web(documents)
    pages = {Path(d.path).stem + ".html": read(real, Path(d.path).stem + ".html") for d in web.documents}
    everything = "".join(pages.values())
    xref = weave.cross_references(web)
    for piece in xref.pieces.values():
        assert f'id="{piece.anchor}"' in pages[piece.page], piece.block.location
    for anchor in xref.examples.values():
        assert f'id="{anchor}"' in everything
    assert everything.count("<math ") >= 100
    check_links(real, PROJECT_ROOT)
    index = read(real, "index.html")
    import ident

    for name in ident.__all__:
        assert f"<code>{name}" in index, name
    notebooks = sorted(p.name for p in (real / "notebooks").glob("*.ipynb"))
    assert notebooks == sorted(Path(d.path).stem + ".ipynb" for d in web.documents)
    usage = json.loads(read(real, "notebooks/07-usage.ipynb"))
    outputs = [o for c in usage["cells"] if c["cell_type"] == "code" for o in c["outputs"]]
    assert any("max |R - R_true|" in "".join(o.get("text", "")) for o in outputs)


def test_the_notebooks_carry_the_values_the_pages_show(real) -> None:
    """No inline value is left as `{python} expression` in a notebook's Markdown, and each value the
    page shows as plain text (no formula in it) is in the notebook's Markdown too."""
    shown = 0
    for path in sorted((real / "notebooks").glob("*.ipynb")):
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
        markdown = "\n".join("".join(cell["source"]) for cell in cells if cell["cell_type"] == "markdown")
        assert tangle.parse_document(markdown, path.name).inline_values() == [], path.name
        page = read(real, path.stem + ".html")
        for value in re.findall(r'<span class="computed" title="[^"]*">([^<]*)</span>', page):
            assert html.unescape(value) in markdown, f"{path.name}: {value!r} is on the page, not in the notebook"
            shown += 1
    assert shown >= 50


def test_the_woven_document_stays_small(real) -> None:
    size = sum(p.stat().st_size for p in real.rglob("*") if p.is_file())
    assert size < 5_000_000, f"docs/ would be {size / 1e6:.1f} MB"


def test_the_commands_in_docs_readme_exist() -> None:
    """docs/README.md is written by hand (the weave leaves it alone): each command its shell block
    gives runs (with --help appended, so that nothing is written)."""
    text = (PROJECT_ROOT / "docs" / "README.md").read_text(encoding="utf-8")
    commands = [command.strip() for block in re.findall(r"```sh\n(.*?)```", text, re.S)
                for line in block.splitlines() for command in line.split("&&") if command.strip()]
    assert commands
    for command in commands:
        program, *arguments = command.split()
        assert program == "python", command
        done = subprocess.run([sys.executable, *arguments, "--help"], cwd=PROJECT_ROOT, capture_output=True,
                              text=True, timeout=120)
        assert done.returncode == 0, f"docs/README.md: {command}: {done.stdout}{done.stderr}"


# --------------------------------------------------------------------------------------------
# the apparatus of a paper: parts, numbered formulas, figures and tables, citations, mentions


PAPER = {
    "01-front.md": '''\
# The front matter

The front cites [@alpha] and names `03-paper.md`, 03-paper.md#the-method and `07-missing.md`.

$$
a = b
$$

```python
# example: a first figure
import matplotlib.pyplot as plt

plt.figure(figsize=(1, 1))
```
''',
    "02-intro.md": '''\

<!-- part: Part I. The paper -->
# Introduction

See @eq:sysid, @eq:second, @fig:line, @tbl:data and @tbl:computed [@alpha; @beta], not `@eq:sysid`.

$$
x = 1 \\notag
$$

$$
y = 2 \\quad $$ {#eq:second}

$$ z = 3 $$ {#eq:inline}
''',
    "03-paper.md": '''\
# The paper

## The method

$$
w \\in \\mathcal{B} \\tag{SYSID}
$$ {#eq:sysid}

$$
v = 4
$$

| a | b |
|---|---|
| 1 | 2 |

Table: Some *data*, cited [@beta]. {#tbl:data}

```python
# example: draws a line
import matplotlib.pyplot as plt

# caption: A line, see @eq:inline. {#fig:line}
plt.figure(figsize=(1, 1))
plt.plot([1, 2])
table_value = "| x | y |\\n|---|---|\\n| 3 | 4 |"
```

`{python} table_value`

Table: A computed table. {#tbl:computed}

```python .noeval
# <<src/ident/paper.py>>=
# the reasons are in 02-intro.md
NAME = "04-refs.md"
```
''',
    "04-refs.md": '''\
<!-- part: Part II. Back matter -->
# References

- {#ref:alpha} A. Author. *A book*. 2001.
- {#ref:beta} B. Author. An article. 2002.
- {#ref:gamma} C. Author. Never cited.
''',
}


def make_documents(root: Path, documents: dict[str, str]) -> Path:
    (root / "literate").mkdir(parents=True)
    for name, text in documents.items():
        (root / "literate" / name).write_text(text, encoding="utf-8")
    outputs, _ = tangle.tangle(root)
    tangle.write(root, outputs)
    return root


@pytest.fixture(scope="module")
def paper(tmp_path_factory) -> tuple[Path, list[str]]:
    root = make_documents(tmp_path_factory.mktemp("paper"), PAPER)
    woven = weave.Weave(root, root / "docs", notebooks=False)
    woven.run()
    return root / "docs", woven.warnings


def test_parts_group_the_contents_and_head_their_pages(paper) -> None:
    out, _ = paper
    index = read(out, "index.html")
    contents = index[index.index('<nav class="toc"'):]
    assert contents.index('href="01-front.html"') < contents.index('<h3 class="part">Part I. The paper</h3>')
    assert contents.index("Part I. The paper") < contents.index('href="02-intro.html"') \
        < contents.index('href="03-paper.html"') < contents.index("Part II. Back matter") \
        < contents.index('href="04-refs.html"') < contents.index('<h3 class="part">Indexes</h3>')
    assert '<ol start="2">' in contents and '<ol start="4">' in contents
    assert 'class="part-name"' not in read(out, "01-front.html")
    for page, part in (("02-intro.html", "Part I. The paper"), ("03-paper.html", "Part I. The paper"),
                       ("04-refs.html", "Part II. Back matter")):
        text = read(out, page)
        assert f'<div class="part-name">{part}</div>\n<h1' in text
        assert "<!--" not in text and "part:" not in text


def test_formulas_are_numbered_across_documents_with_tags_and_labels(paper) -> None:
    out, _ = paper
    front, intro, body = read(out, "01-front.html"), read(out, "02-intro.html"), read(out, "03-paper.html")
    assert '<span class="equation-number">(1)</span>' in front
    assert intro.count('class="equation-number"') == 2  # \notag: no number, and no \notag in the formula
    assert '<div class="equation" id="eq-second"><div class="math-display"><math' in intro
    assert '<span class="equation-number">(2)</span>' in intro.split('id="eq-second"')[1].split("</div>\n")[0]
    assert 'id="eq-inline"' in intro and '<span class="equation-number">(3)</span>' in intro
    assert '<div class="equation" id="eq-sysid">' in body and '<span class="equation-number">(SYSID)</span>' in body
    assert '<span class="equation-number">(4)</span>' in body  # a tag takes no number
    assert "{#eq:" not in intro + body and "notag" not in intro and "(SYSID)</mtext>" not in body
    assert '<a class="xref" href="03-paper.html#eq-sysid">(SYSID)</a>' in intro
    assert '<a class="xref" href="02-intro.html#eq-second">(2)</a>' in intro
    assert "not <code>@eq:sysid</code>" in intro  # code is not a reference
    check_links(out)


def test_figures_are_numbered_across_documents_and_labelled(paper) -> None:
    out, _ = paper
    front, intro, body = read(out, "01-front.html"), read(out, "02-intro.html"), read(out, "03-paper.html")
    assert '<figure class="example-figure" id="figure-1">' in front and "Figure 1.</span>" in front
    assert '<figure class="example-figure" id="fig-line">' in body
    assert ('<span class="figure-number">Figure 2.</span> A line, see '
            '<a class="xref" href="02-intro.html#eq-inline">(3)</a>.</figcaption>') in body
    assert "{#fig:" not in body and 'alt="A line, see (3)."' in body
    assert '<a class="xref" href="03-paper.html#fig-line">Figure 2</a>' in intro


def test_tables_with_a_caption_paragraph_are_numbered(paper) -> None:
    out, _ = paper
    body, intro = read(out, "03-paper.html"), read(out, "02-intro.html")
    assert ('<table id="tbl-data">\n<caption><span class="table-number">Table 1.</span> Some <em>data</em>, '
            'cited [<a class="citation" href="04-refs.html#ref-beta">2</a>].</caption>\n<thead>') in body
    computed = body.split('<div class="computed" title="table_value">')[1].split("</div>")[0]
    assert '<table id="tbl-computed">\n<caption><span class="table-number">Table 2.</span> A computed table.' \
        in computed and "<td>3</td>" in computed
    assert "Table:" not in body and "{#tbl:" not in body
    assert '<a class="xref" href="03-paper.html#tbl-data">Table 1</a>' in intro
    assert '<a class="xref" href="03-paper.html#tbl-computed">Table 2</a>' in intro


def test_citations_link_to_the_numbered_bibliography(paper) -> None:
    out, warnings = paper
    refs, intro = read(out, "04-refs.html"), read(out, "02-intro.html")
    assert '<ul class="bibliography">' in refs
    assert '<li id="ref-alpha"><span class="ref-number">[1]</span> A. Author. <em>A book</em>. 2001.</li>' in refs
    assert '<li id="ref-gamma"><span class="ref-number">[3]</span> C. Author.' in refs and "{#ref:" not in refs
    assert ('[<a class="citation" href="04-refs.html#ref-alpha">1</a>, '
            '<a class="citation" href="04-refs.html#ref-beta">2</a>]') in intro
    assert '[<a class="citation" href="04-refs.html#ref-alpha">1</a>]' in read(out, "01-front.html")
    assert "literate/04-refs.md:6: warning: bibliography entry 'gamma' is never cited" in warnings
    assert not [w for w in warnings if "'alpha'" in w or "'beta'" in w]


def test_mentions_of_documents_become_links_named_by_their_titles(paper) -> None:
    out, warnings = paper
    front, body = read(out, "01-front.html"), read(out, "03-paper.html")
    assert 'names <a class="document" href="03-paper.html">The paper</a>, ' in front
    assert '<a class="document" href="03-paper.html#the-method">The paper</a> and' in front
    assert "<code>07-missing.md</code>" in front
    assert "literate/01-front.md:3: warning: 07-missing.md is not a literate document" in warnings
    assert '<span class="c1"># the reasons are in <a href="02-intro.html">02-intro.md</a></span>' in body
    assert '<span class="s2">"<a href="04-refs.html">04-refs.md</a>"</span>' in body


def test_mentions_of_repository_files_become_links_from_the_pages(tmp_path) -> None:
    # a reader of docs/ in a clone opens ../reference/README.md; a path that does not exist stays text
    root = make_documents(tmp_path, {"01-a.md": "# A\n\nSee `reference/README.md`, benchmarks/run.py, "
                                                 "`benchmarks/missing.py` and docs/daisy/.\n"})
    for path in ("reference/README.md", "benchmarks/run.py", "docs/daisy/table.md"):
        (root / path).parent.mkdir(parents=True, exist_ok=True)
        (root / path).write_text("x\n")
    weave.Weave(root, root / "docs", notebooks=False).run()
    page = read(root / "docs", "01-a.html")
    assert '<a class="file" href="../reference/README.md"><code>reference/README.md</code></a>' in page
    assert '<a class="file" href="../benchmarks/run.py">benchmarks/run.py</a>' in page
    assert "<code>benchmarks/missing.py</code>" in page and 'href="../benchmarks/missing.py"' not in page
    assert "docs/daisy/." in page and 'href="daisy/"' not in page  # a folder stays text


@pytest.mark.parametrize("name, text, error", [
    ("unknown label", "See @eq:nope.\n", "literate/01-a.md:3: unknown label 'eq:nope'"),
    ("unknown figure", "See @fig:nope.\n", "literate/01-a.md:3: unknown label 'fig:nope'"),
    ("unknown key", "As in [@x; @nope].\n\n- {#ref:x} X.\n", "literate/01-a.md:3: unknown bibliography entry 'nope'"),
    ("duplicate label", "$$\na\n$$ {#eq:a}\n\n$$\nb\n$$ {#eq:a}\n",
     "literate/01-a.md:9: duplicate label {#eq:a} (first at literate/01-a.md:5)"),
    ("duplicate table", "| a |\n|---|\n\nTable: one {#tbl:t}\n\n| b |\n|---|\n\nTable: two {#tbl:t}\n",
     "literate/01-a.md:11: duplicate label {#tbl:t} (first at literate/01-a.md:6)"),
    ("duplicate key", "[@k]\n\n- {#ref:k} One.\n- {#ref:k} Two.\n",
     "literate/01-a.md:6: duplicate label {#ref:k} (first at literate/01-a.md:5)"),
    ("label after no formula", "costs $$ {#eq:a}\n", "literate/01-a.md:3: the label {#eq:a} closes no display formula"),
    ("label on no number", "$$\na \\notag\n$$ {#eq:a}\n", "literate/01-a.md:5: the formula labelled {#eq:a} has no number"),
])
def test_unknown_and_duplicate_labels_name_their_line(tmp_path, name, text, error) -> None:
    root = make_documents(tmp_path / "project", {"01-a.md": "# A\n\n" + text})
    with pytest.raises(weave.WeaveError) as raised:
        weave.Weave(root, tmp_path / "out", notebooks=False).run()
    assert error in str(raised.value)
    assert not (tmp_path / "out").exists()


def test_misplaced_markup_and_missing_documents_are_warnings_with_their_line(tmp_path) -> None:
    text = ("# A\n\n<!-- part: Too late -->\n\nTable: no table above\n\n[gone](09-gone.md)\n\n"
            "```sh\ncat 08-gone.md\n```\n")
    root = make_documents(tmp_path / "project", {"01-a.md": text})
    woven = weave.Weave(root, tmp_path / "out", notebooks=False)
    woven.run()
    assert woven.warnings == [
        "literate/01-a.md:3: warning: a part marker is read only on the first line of a document, before its "
        "title; this one is ignored",
        "literate/01-a.md:5: warning: a 'Table:' caption that follows no table (it belongs right after its "
        "table, after one blank line)",
        "literate/01-a.md:10: warning: 08-gone.md is not a literate document",
        "literate/01-a.md:7: warning: a link to 09-gone.md, which is not a literate document",
    ]
    assert 'class="part-name"' not in read(tmp_path / "out", "01-a.html")


# --------------------------------------------------------------------------------------------
# issue 32 (the literate tools): the weave removes or replaces only files it wrote itself, an
# interrupted weave leaves no partial file, a bad --root or --out is refused first, and a chunk that
# expands exponentially is refused with a clear error


def user_files(out: Path) -> dict[str, bytes]:
    """A user's own files in the places the weave writes to."""
    files = {"figures/mine.png": b"\x89PNG user", "figures/sub/deep.png": b"deep", "notebooks/mine.ipynb": b"{}",
             "notebooks/notes.txt": b"notes", "notes.html": b"<html>my own page</html>", "README.md": b"kept",
             "daisy/table.csv": b"a,b"}
    for name, data in files.items():
        (out / name).parent.mkdir(parents=True, exist_ok=True)
        (out / name).write_bytes(data)
    return files


def weave_at(root: Path, out: Path, *options: str) -> int:
    return weave.main(["--root", str(root), "--out", str(out), *options])


def test_a_users_files_in_the_output_folder_are_never_removed(tmp_path) -> None:
    root = make_project(tmp_path / "project")
    out = tmp_path / "out"
    mine = user_files(out)  # before the first weave: no manifest yet
    assert weave_at(root, out) == 0
    assert weave_at(root, out, "--no-notebooks") == 0  # a weave that writes fewer files
    assert weave_at(root, out) == 0
    assert {name: (out / name).read_bytes() for name in mine} == mine


def test_the_manifest_lists_what_the_weave_wrote_and_its_stale_files_go(tmp_path) -> None:
    root = make_project(tmp_path / "project")
    out = tmp_path / "out"
    assert weave_at(root, out) == 0
    written = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file() and p.name != weave.MANIFEST)
    manifest = json.loads((out / weave.MANIFEST).read_text(encoding="utf-8"))
    assert manifest == {"generator": weave.GENERATOR, "files": written}
    assert "figures/own-figure.png" in written and "notebooks/01-first.ipynb" in written
    mine = user_files(out)
    (root / "literate/01-first.md").write_text(FIRST.replace('own.savefig(Path(os.environ["IDENT_FIGURES"]) / '
                                                             '"own-figure.png")', ""), encoding="utf-8")
    assert weave_at(root, out, "--no-notebooks") == 0
    assert not (out / "figures/own-figure.png").exists() and not (out / "notebooks/01-first.ipynb").exists()
    assert {name: (out / name).read_bytes() for name in mine} == mine
    manifest = json.loads((out / weave.MANIFEST).read_text(encoding="utf-8"))
    assert "figures/own-figure.png" not in manifest["files"] and "notebooks/mine.ipynb" not in manifest["files"]


def test_without_a_manifest_the_marked_pages_and_what_they_link_to_are_the_weaves(tmp_path) -> None:
    """A folder woven before the weave kept a manifest (docs/ up to issue 32): the pages carrying the
    weave's mark, the style sheet and the figures and notebooks those pages link to are its own."""
    root = make_project(tmp_path / "project")
    out = tmp_path / "out"
    assert weave_at(root, out) == 0
    (out / weave.MANIFEST).unlink()
    mine = user_files(out)
    (root / "literate/01-first.md").write_text(FIRST.replace('own.savefig(Path(os.environ["IDENT_FIGURES"]) / '
                                                             '"own-figure.png")', ""), encoding="utf-8")
    (root / "literate/02-second.md").unlink()
    assert weave_at(root, out, "--no-notebooks") == 0
    assert not (out / "figures/own-figure.png").exists()  # linked from the earlier page: the weave's
    assert not (out / "02-second.html").exists() and not (out / "notebooks/02-second.ipynb").exists()
    assert {name: (out / name).read_bytes() for name in mine} == mine


@pytest.mark.parametrize("name, data", [
    ("index.html", b"<html>my own index</html>"),  # no weave's mark
    ("style.css", b"body { color: red }"),
    ("notebooks/01-first.ipynb", b"{}"),
    ("figures/own-figure.png", b"mine"),  # known only once the examples ran
    ("02-second.html", None),  # a folder where a page belongs
])
def test_a_file_the_weave_did_not_write_is_not_replaced(tmp_path, capsys, name, data) -> None:
    root = make_project(tmp_path / "project")
    out = tmp_path / "out"
    if data is None:
        (out / name).mkdir(parents=True)
    else:
        (out / name).parent.mkdir(parents=True, exist_ok=True)
        (out / name).write_bytes(data)
    before = snapshot(out)
    capsys.readouterr()
    assert weave_at(root, out) == 2
    error = capsys.readouterr().err.splitlines()[-1]  # after the warnings of the small project
    assert error.startswith(f"weave: error: --out {out.resolve()}: 1 file(s) the weave writes exist there")
    assert f"manifest.json): {name}; move them away" in error
    assert snapshot(out) == before and (out / name).exists() and sorted(p.name for p in out.iterdir()) == sorted(
        {name.split("/")[0]})
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out-weave-")]


def test_a_manifest_naming_other_files_removes_none_of_them(tmp_path, capsys) -> None:
    root = make_project(tmp_path / "project")
    out = tmp_path / "out"
    assert weave_at(root, out) == 0
    mine = user_files(out)
    (tmp_path / "outside.txt").write_text("outside\n")
    (out / "figures/link.png").symlink_to(tmp_path / "outside.txt")
    hostile = ["../outside.txt", str(tmp_path / "outside.txt"), "README.md", "daisy/table.csv", "notes.html",
               "figures/link.png", "figures/../README.md", "notebooks/notes.txt", weave.MANIFEST]
    (out / weave.MANIFEST).write_text(weave.manifest_text(hostile), encoding="utf-8")
    capsys.readouterr()
    assert weave_at(root, out) == 0
    assert "lists names the weave does not write, left alone" in capsys.readouterr().err
    assert {name: (out / name).read_bytes() for name in mine} == mine
    assert (out / "figures/link.png").is_symlink() and (tmp_path / "outside.txt").read_text() == "outside\n"


@pytest.mark.parametrize("text", ["not json", '{"files": ["figures/mine.png"]}', '["figures/mine.png"]',
                                  '{"generator": "ident weave.py", "files": "figures/mine.png"}', "\udcff"])
def test_a_damaged_manifest_is_a_warning_and_removes_nothing_unmarked(tmp_path, capsys, text) -> None:
    root = make_project(tmp_path / "project")
    out = tmp_path / "out"
    mine = user_files(out)
    (out / weave.MANIFEST).write_text(text, encoding="utf-8", errors="surrogateescape")
    capsys.readouterr()
    assert weave_at(root, out) == 0
    assert f"{out.resolve() / weave.MANIFEST}: not a manifest of the weave" in capsys.readouterr().err
    assert {name: (out / name).read_bytes() for name in mine} == mine
    assert json.loads((out / weave.MANIFEST).read_text(encoding="utf-8"))["generator"] == weave.GENERATOR


@pytest.mark.parametrize("failure", [KeyboardInterrupt, OSError])
def test_an_install_interrupted_midway_leaves_the_output_as_it_was(tmp_path, monkeypatch, capsys, failure) -> None:
    root = make_project(tmp_path / "project")
    out = tmp_path / "out"
    assert weave_at(root, out) == 0
    user_files(out)
    (root / "literate/01-first.md").write_text(FIRST.replace("hello <world>", "hello again"), encoding="utf-8")
    (root / "literate/02-second.md").unlink()  # a stale page to remove as well
    before = snapshot(out)
    real_replace, moved = os.replace, []

    def replace(source, target):
        if Path(target).is_relative_to(out.resolve()) and len(moved) < 3:  # not the moves that put back
            moved.append(target)
            if len(moved) == 3:  # the manifest and one file are in place
                raise failure(28, "No space left on device") if failure is OSError else failure()
        real_replace(source, target)

    monkeypatch.setattr(weave.os, "replace", replace)
    try:
        status = weave_at(root, out)
    except KeyboardInterrupt:  # the command line must turn it into its exit status
        status = None
    monkeypatch.undo()
    assert len(moved) == 3
    assert status == (130 if failure is KeyboardInterrupt else 1)
    error = capsys.readouterr().err
    assert "left as it was" in error and "Traceback" not in error
    assert snapshot(out) == before
    assert not [p for p in tmp_path.rglob("*") if ".weave-new" in p.name or p.name.startswith(".out-weave-")]


def test_sigterm_interrupts_the_weave_and_leaves_nothing_behind(tmp_path) -> None:
    waiting = tmp_path / "waiting"
    slow = FIRST.replace("shared = 41", f"shared = 41\nimport pathlib, time\npathlib.Path({str(waiting)!r}).touch()\n"
                                        "time.sleep(600)")
    root = make_project(tmp_path / "project", first=slow)
    out = tmp_path / "out"
    mine = user_files(out)
    process = subprocess.Popen([sys.executable, str(PROJECT_ROOT / "weave.py"), "--root", str(root), "--out", str(out)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        for _ in range(1200):  # until the example runs (at most a minute)
            if waiting.exists() or process.poll() is not None:
                break
            time.sleep(0.05)
        assert waiting.exists(), process.communicate(timeout=60)
        process.terminate()
        _, err = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 130 and f"weave: interrupted; {out} is left as it was" in err
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()) == sorted(mine)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out-weave-")]


def test_bad_root_and_out_are_refused_before_anything_runs(tmp_path, capsys) -> None:
    root = make_project(tmp_path / "project")
    missing = tmp_path / "nowhere"
    assert weave.main(["--root", str(missing)]) == 2
    assert capsys.readouterr().err == f"weave: error: --root {missing}: no such folder\n"
    assert not missing.exists()  # no docs/ made inside it
    (tmp_path / "empty").mkdir()
    assert weave.main(["--root", str(tmp_path / "empty")]) == 2
    assert "has no literate/ folder" in capsys.readouterr().err and not (tmp_path / "empty/docs").exists()
    (tmp_path / "a-file").write_text("mine\n")
    assert weave_at(root, tmp_path / "a-file") == 2
    assert capsys.readouterr().err == f"weave: error: --out {tmp_path / 'a-file'} exists and is not a folder; " \
                                      "name a folder (it is made if missing)\n"
    assert (tmp_path / "a-file").read_text() == "mine\n"
    assert weave_at(root, tmp_path / "a-file" / "docs") == 2
    assert capsys.readouterr().err == f"weave: error: --out {tmp_path / 'a-file' / 'docs'}: {tmp_path / 'a-file'} " \
                                      "is a file, not a folder; name a folder\n"
    assert (tmp_path / "a-file").read_text() == "mine\n"


def test_temporaries_a_killed_weave_left_are_removed_by_the_next(tmp_path) -> None:
    root = make_project(tmp_path / "project")
    out = tmp_path / "out"
    assert weave_at(root, out) == 0
    left = [f".{weave.MANIFEST}.weave-new", ".index.html.weave-new", "figures/.own-figure.png.weave-new"]
    for name in left:
        (out / name).write_bytes(b"half")
    (out / ".notes.weave-new").write_bytes(b"mine")  # not a name the weave gives
    assert weave_at(root, out) == 0
    assert not [name for name in left if (out / name).exists()] and (out / ".notes.weave-new").read_bytes() == b"mine"


def test_an_exponential_chunk_stops_the_weave_with_the_clear_error(tmp_path) -> None:
    root = tmp_path / "project"
    (root / "literate").mkdir(parents=True)
    fence = "```"
    doc = f"{fence}python .noeval\n# <<src/ident/m.py>>=\n<<c0>>\n{fence}\n"
    doc += "".join(f"{fence}python .noeval\n# <<c{k}>>=\n<<c{k + 1}>>\n<<c{k + 1}>>\n{fence}\n" for k in range(60))
    doc += f"{fence}python .noeval\n# <<c60>>=\nx = 1\n{fence}\n"
    (root / "literate/01-a.md").write_text(doc, encoding="utf-8")
    assert len(doc) < 4000
    resource = pytest.importorskip("resource")

    def limit_memory() -> None:  # a MemoryError, not a machine out of memory, if the limit is missing
        resource.setrlimit(resource.RLIMIT_AS, (2**31, 2**31))

    done = subprocess.run([sys.executable, str(PROJECT_ROOT / "weave.py"), "--root", str(root), "--out",
                           str(tmp_path / "out")], capture_output=True, text=True, timeout=120, preexec_fn=limit_memory)
    assert done.returncode == 1, done.stderr[-2000:]
    assert done.stderr.startswith("weave: error: literate/01-a.md:1: chunk <<src/ident/m.py>> expands to about "
                                  "10^18 lines")
    assert "MAX_EXPANDED_LINES" in done.stderr and len(done.stderr.splitlines()) == 1
    assert not (tmp_path / "out").exists()
