#!/usr/bin/env python3
"""Weave the literate sources of ident (``literate/*.md``) into a browsable document in ``docs/``:
the command line.

Usage::

    python weave.py                  # write docs/
    python weave.py --out /tmp/docs  # somewhere else
    python weave.py --no-notebooks   # pages only

The code is in ``literate_tools/`` (``site.py`` has the whole weave and describes it); the names of
its modules are available here too (``import weave``), as before the split.  Needs markdown-it-py,
mdit-py-plugins, latex2mathml, Pygments, matplotlib and jupytext (the ``docs`` extra of the package).
"""
import sys

from literate_tools.xref import *  # noqa: F401,F403  (the names of the weave's modules, for ``import weave``)
from literate_tools.examples import *  # noqa: F401,F403
from literate_tools.mathml import *  # noqa: F401,F403
from literate_tools.render import *  # noqa: F401,F403
from literate_tools.site import *  # noqa: F401,F403
from literate_tools.site import main

if __name__ == "__main__":
    sys.exit(main())
