"""The woven pages in a real browser: headless Chromium loads each page of a fresh weave of
``literate/`` and a check script, injected into a test copy of the page, reports what the reader
would see: resources that failed to load, images and their sizes, the MathML formulas and their
boxes, in-page links without a target.  Cross-page links are then checked against the ids each
page reported.  A screenshot of the first screen of the index and of the first document is kept
for inspection (in the test's temporary folder, or in ``$IDENT_SCREENSHOT_DIR``).

Chromium is Debian's ``chromium`` (``apt-get install chromium``), or the program named by
``$IDENT_CHROMIUM``; without one the tests are skipped.  It runs with no network use of its own
(the flags below) and loads the pages from ``file://`` URLs.
"""
from __future__ import annotations

import html
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import PROJECT_ROOT

CHROMIUM_FLAGS = [
    "--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-default-apps", "--disable-extensions", "--hide-scrollbars", "--mute-audio",
]

EARLY_SCRIPT = """<script>
window.__failed = [];
window.addEventListener("error", function (event) {
  var t = event.target;
  if (t && t !== window && (t.src || t.href)) { window.__failed.push(t.src || t.href); }
}, true);
</script>"""

CHECK_SCRIPT = """<script>
window.addEventListener("load", function () {
  var r = {failed: window.__failed.slice(), images: [], math: {count: 0, empty: [], notMath: []},
           localLinksBroken: [], crossLinks: [], ids: [], stylesheets: [], resources: [], textWidth: 0};
  document.querySelectorAll("img").forEach(function (img) {
    var box = img.getBoundingClientRect();
    r.images.push({src: img.getAttribute("src"), complete: img.complete, naturalWidth: img.naturalWidth,
                   naturalHeight: img.naturalHeight, width: box.width, height: box.height});
  });
  document.querySelectorAll("math").forEach(function (m, k) {
    var box = m.getBoundingClientRect();
    r.math.count += 1;
    if (!(box.width > 0 && box.height > 0)) { r.math.empty.push(k); }
    if (getComputedStyle(m).display.indexOf("math") < 0) { r.math.notMath.push(getComputedStyle(m).display); }
  });
  document.querySelectorAll("a[href]").forEach(function (a) {
    var href = a.getAttribute("href");
    if (href.charAt(0) === "#") {
      if (!document.getElementById(decodeURIComponent(href.slice(1)))) { r.localLinksBroken.push(href); }
    } else if (!/^[a-z]+:/i.test(href)) {
      r.crossLinks.push(href);
    }
  });
  document.querySelectorAll("[id]").forEach(function (e) { r.ids.push(e.id); });
  document.querySelectorAll("link[rel=stylesheet]").forEach(function (l) {
    r.stylesheets.push({href: l.getAttribute("href"), loaded: !!l.sheet});
  });
  performance.getEntriesByType("resource").forEach(function (e) {
    r.resources.push({name: e.name, type: e.initiatorType});
  });
  var p = document.querySelector("main > p");
  if (p) { r.textWidth = p.getBoundingClientRect().width; r.fontSize = parseFloat(getComputedStyle(p).fontSize); }
  var out = document.createElement("pre");
  out.id = "check-results";
  out.textContent = JSON.stringify(r);
  document.body.appendChild(out);
});
</script>"""


def find_chromium() -> str | None:
    named = os.environ.get("IDENT_CHROMIUM")
    if named:
        return named if shutil.which(named) else None
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        path = shutil.which(name)
        if path:
            return path
    return None


pytest.importorskip("latex2mathml", reason="the weave needs latex2mathml (the docs extra)")
CHROMIUM = find_chromium()
pytestmark = pytest.mark.skipif(
    CHROMIUM is None,
    reason="no headless browser: install Debian's chromium (apt-get install -y chromium) or set IDENT_CHROMIUM",
)


def chromium(args: list[str], profile: Path, timeout: float = 120) -> subprocess.CompletedProcess:
    command = [CHROMIUM, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL)


@pytest.fixture(scope="module")
def woven(tmp_path_factory) -> Path:
    """A fresh weave of the real literate/ (pages and figures; the notebooks are not needed here)."""
    out = tmp_path_factory.mktemp("woven")
    done = subprocess.run([sys.executable, "weave.py", "--out", str(out), "--no-notebooks"],
                          cwd=PROJECT_ROOT, capture_output=True, text=True, timeout=600)
    if done.returncode != 0 and "did not run; docs/ is left as it was" in done.stderr:
        pytest.skip("the weave stopped because examples failed (see tests/test_examples.py)")
    assert done.returncode == 0, f"the weave failed:\n{done.stdout}\n{done.stderr}"
    return out


@pytest.fixture(scope="module")
def checked(woven, tmp_path_factory) -> dict[str, dict]:
    """Each page's check results, from a test copy of the page with the check script injected."""
    profile = tmp_path_factory.mktemp("chromium-profile")
    results = {}
    for page in sorted(woven.glob("*.html")):
        copy = page.with_name(f"check-{page.name}")
        text = page.read_text(encoding="utf-8")
        text = text.replace("<head>", "<head>\n" + EARLY_SCRIPT, 1)
        text = text.replace("</body>", CHECK_SCRIPT + "\n</body>", 1)
        copy.write_text(text, encoding="utf-8")
        done = chromium(["--virtual-time-budget=5000", "--dump-dom", copy.as_uri()], profile)
        copy.unlink()
        found = re.search(r'<pre id="check-results">(.*?)</pre>', done.stdout, re.S)
        assert found, (f"{page.name}: the check script reported nothing (exit {done.returncode}):\n"
                       f"{done.stderr[-2000:]}")
        results[page.name] = json.loads(html.unescape(found[1]))
    return results


def test_every_page_was_checked(woven, checked) -> None:
    assert "index.html" in checked and len(checked) >= 3


def test_no_resource_fails_to_load(checked) -> None:
    for page, r in checked.items():
        assert r["failed"] == [], f"{page}: failed to load {r['failed']}"
        assert r["stylesheets"] and all(s["loaded"] for s in r["stylesheets"]), f"{page}: {r['stylesheets']}"
        names = [e["name"] for e in r["resources"]]
        assert all(n.startswith("file://") for n in names), f"{page}: loads from elsewhere: {names}"


def test_images_load_with_a_size(checked) -> None:
    images = [(page, image) for page, r in checked.items() for image in r["images"]]
    for page, image in images:
        assert image["complete"] and image["naturalWidth"] > 0 and image["naturalHeight"] > 0, (page, image)
        assert image["width"] > 0 and image["height"] > 0, (page, image)
        assert image["width"] <= 64 * 16 + 1, f"{page}: image wider than the page: {image}"


def test_mathematics_is_rendered_as_mathml(checked) -> None:
    assert checked["02-method.html"]["math"]["count"] >= 10
    for page, r in checked.items():
        assert r["math"]["empty"] == [], f"{page}: formulas with an empty box: {r['math']['empty'][:10]}"
        assert r["math"]["notMath"] == [], f"{page}: <math> not laid out as MathML: {r['math']['notMath'][:5]}"


def test_every_link_has_a_target(woven, checked) -> None:
    for page, r in checked.items():
        assert r["localLinksBroken"] == [], f"{page}: links to missing anchors: {r['localLinksBroken'][:10]}"
        for href in r["crossLinks"]:
            target, _, anchor = href.partition("#")
            # a link to a repository file (../reference/...) or to the runner's docs/daisy/ is relative to
            # the repository's docs/, where the pages live; every other target is written by the weave
            base = PROJECT_ROOT / "docs" if target.startswith(("../", "daisy/")) else woven
            assert (base / target).is_file(), f"{page}: link to a missing file {href}"
            if anchor and target.endswith(".html"):
                assert anchor in checked[target]["ids"], f"{page}: link to a missing anchor {href}"


def test_ids_are_unique(checked) -> None:
    for page, r in checked.items():
        duplicates = sorted({i for i in r["ids"] if r["ids"].count(i) > 1})
        assert duplicates == [], f"{page}: duplicate ids {duplicates}"


def test_text_width_is_limited(checked) -> None:
    r = checked["01-introduction.html"]
    assert 0 < r["textWidth"] <= 46 * r["fontSize"], r


WIDTH_SCRIPT = """<script>
window.addEventListener("load", function () {
  function scrolls(e) {  // inside a box that scrolls or clips on its own (a formula, code, a table)
    for (var a = e.parentElement; a && a.tagName !== "MAIN"; a = a.parentElement) {
      var o = getComputedStyle(a).overflowX;
      if (o === "auto" || o === "scroll" || o === "hidden") { return true; }
    }
    return false;
  }
  var beyond = [], formulas = [];
  document.querySelectorAll("main *").forEach(function (e) {
    var box = e.getBoundingClientRect();
    if (box.right > window.innerWidth + 1 && !scrolls(e)) {
      beyond.push(e.tagName.toLowerCase() + ": " + (e.textContent || "").slice(0, 60));
    }
  });
  document.querySelectorAll("math[display=block]").forEach(function (m) {
    var box = m.parentElement, style = getComputedStyle(box);
    formulas.push({text: m.textContent.replace(/\\s+/g, " ").slice(0, 60), width: box.scrollWidth,
                   column: box.clientWidth, own: box.matches(".math-display") && box.childElementCount === 1,
                   overflow: style.overflowX, maxWidth: style.maxWidth});
  });
  var result = JSON.stringify({beyond: beyond.slice(0, 10), count: beyond.length, formulas: formulas,
                               page: document.documentElement.scrollWidth, window: window.innerWidth});
  if (window.parent !== window) { window.parent.postMessage(result, "*"); }
  var out = document.createElement("pre");
  out.id = "width-results";
  out.textContent = result;
  document.body.appendChild(out);
});
</script>"""

# a window of any width: the page in a frame that wide (headless Chromium makes no window under 500 px);
# the frame passes the page's results up to the document that --dump-dom prints
FRAME = """<!DOCTYPE html><html><body style="margin:0">
<iframe src="{page}" style="width:{width}px;height:900px;border:0"></iframe>
<script>window.addEventListener("message", function (event) {{
  var out = document.createElement("pre"); out.id = "width-results"; out.textContent = event.data;
  document.body.appendChild(out);
}});</script></body></html>"""

WIDTHS = (1280, 400)


@pytest.fixture(scope="module")
def widths(woven, tmp_path_factory) -> dict[int, dict[str, dict]]:
    """Each page's layout at each width of WIDTHS: what runs beyond the window, and the boxes of the
    display formulas."""
    profile = tmp_path_factory.mktemp("chromium-width")
    results: dict[int, dict[str, dict]] = {}
    for width in WIDTHS:
        for page in sorted(woven.glob("*.html")):
            copy, frame = page.with_name(f"width-{page.name}"), page.with_name(f"frame-{page.name}")
            copy.write_text(page.read_text(encoding="utf-8").replace("</body>", WIDTH_SCRIPT + "\n</body>", 1),
                            encoding="utf-8")
            frame.write_text(FRAME.format(page=copy.name, width=width), encoding="utf-8")
            done = chromium([f"--window-size={width + 20},900", "--virtual-time-budget=5000", "--dump-dom",
                             frame.as_uri()], profile)
            copy.unlink()
            frame.unlink()
            found = re.search(r'<pre id="width-results">(.*?)</pre>', done.stdout, re.S)
            assert found, f"{page.name}: no result at width {width}: {done.stderr[-1000:]}"
            results.setdefault(width, {})[page.name] = json.loads(html.unescape(found[1]))
            assert results[width][page.name]["window"] == width, "the frame is not as wide as asked"
    return results


@pytest.mark.parametrize("width", WIDTHS)
def test_wide_formulas_and_tables_fit_or_scroll_within_themselves(widths, width) -> None:
    """At a desktop width and a phone's, nothing makes the page wider than the window: a formula, a
    table or code wider than the column scrolls within its own box."""
    for page, result in widths[width].items():
        shown = {k: v for k, v in result.items() if k != "formulas"}
        assert result["count"] == 0 and result["page"] <= result["window"], f"{page} at {width} px: {shown}"


def test_every_display_formula_scrolls_in_its_own_box(widths) -> None:
    formulas = [(page, f) for page, result in widths[400].items() for f in result["formulas"]]
    assert formulas, "no display formula found"
    for page, formula in formulas:
        assert formula["own"] and formula["overflow"] == "auto" and formula["maxWidth"] == "100%", (page, formula)
        assert formula["column"] <= 400, (page, formula)


def display_formulas(page: str) -> list[tuple[int, str]]:
    """(line, LaTeX) of each display formula of the literate document of a page, in order."""
    import weave

    path = PROJECT_ROOT / "literate" / page.replace(".html", ".md")
    if not path.is_file():
        return []
    tokens = weave.make_markdown().parse(path.read_text(encoding="utf-8"))
    return [(token.map[0] + 1, token.content.strip()) for token in tokens if token.type == "math_block"]


def test_no_display_formula_is_wider_than_its_column(widths) -> None:
    """At 1280 px no display formula needs its scroll bar: each fits the text column."""
    wide = []
    for page, result in widths[1280].items():
        sources = display_formulas(page)
        if len(sources) != len(result["formulas"]):  # a formula in a computed value: no line to name
            sources = [(0, formula["text"]) for formula in result["formulas"]]
        for (line, latex), formula in zip(sources, result["formulas"]):
            if formula["width"] > formula["column"] + 1:
                wide.append((f"literate/{page.replace('.html', '.md')}:{line}", " ".join(latex.split())[:60],
                             f"{formula['width']} px in {formula['column']} px"))
    listing = "\n".join("  ".join(entry) for entry in wide)
    assert wide == [], "display formulas wider than the column at 1280 px:\n" + listing


def test_screenshots_at_desktop_and_phone_widths(woven, tmp_path_factory) -> None:
    folder = Path(os.environ.get("IDENT_SCREENSHOT_DIR") or tmp_path_factory.mktemp("screenshots"))
    folder.mkdir(parents=True, exist_ok=True)
    profile = tmp_path_factory.mktemp("chromium-screenshot-profile")
    for name in ("index.html", "01-introduction.html", "04-daisy.html", "23-solver-inner-problem.html"):
        for width in (1280, 500):
            target = folder / name.replace(".html", f"-{width}.png")
            done = chromium([f"--window-size={width},900", f"--screenshot={target}", (woven / name).as_uri()],
                            profile)
            assert target.is_file() and target.stat().st_size > 10_000, done.stderr[-2000:]
            print(f"screenshot of {name} at {width} px: {target}")
