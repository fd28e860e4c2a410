"""LaTeX to MathML (latex2mathml, with the corrections MathML Core needs), so that the woven pages
show mathematics with neither JavaScript nor a network connection.
"""
from __future__ import annotations

import contextlib
import re
import warnings



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
