"""The literate tooling of ident: the programs behind ``python tangle.py`` and ``python weave.py``.

The modules, each importing only those above it:

* ``chunks``: the parser: Markdown documents with named chunks, examples and inline values read
  into a checked ``Web`` (standard library only);
* ``tangle``: the root chunks expanded and written to ``src/ident/`` (standard library only);
* ``xref``: cross references between chunks (numbers, anchors, "used in");
* ``examples``: the example runner, which ``tests/test_examples.py`` imports alone;
* ``mathml``: LaTeX to MathML;
* ``render``: one document to one HTML page, with the apparatus of a paper;
* ``site``: the whole weave: every page, ``index.html``, the notebooks, the style sheet
  (``site.css``, beside this file) and the output folder's manifest.

``tangle.py`` and ``weave.py`` at the project root are the command lines; they run from a plain
clone (nothing installed), which puts the project root, and so this package, on the import path.
"""
