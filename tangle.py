#!/usr/bin/env python3
"""Tangle the literate sources of ident (``literate/*.md``) into ``src/ident/``: the command line.

Usage::

    python tangle.py            # write every root chunk to its file
    python tangle.py --check    # exit 1 and name each file that differs from the literate sources
    python tangle.py --where src/ident/hankel.py:42   # which literate line produced that line
    python tangle.py --where /abs/path/src/ident/hankel.py:42   # the same, from a traceback

The code is in ``literate_tools/chunks.py`` (the parser) and ``literate_tools/tangle.py`` (the
tangler); their names are available here too (``import tangle``), as before the split.
Standard library only: the tangler must run before anything is installed.
"""
import sys

from literate_tools.chunks import *  # noqa: F401,F403  (the names of the parser, for ``import tangle``)
from literate_tools.tangle import *  # noqa: F401,F403
from literate_tools.tangle import main

if __name__ == "__main__":
    sys.exit(main())
