"""Helpers of the documentation build (not part of the bvpnav package)."""

from __future__ import annotations

import jupytext

KERNELSPEC = {"name": "python3", "display_name": "Python 3", "language": "python"}
LANGUAGE_INFO = {"name": "python", "pygments_lexer": "ipython3"}


def read_percent_script(text: str):
    """Read a jupytext "percent" script as a notebook that says it is Python.

    The tutorial scripts carry no kernel metadata; without it myst-nb cannot choose a
    lexer for the code cells of a page that is not executed.
    """
    nb = jupytext.reads(text, fmt="py:percent")
    nb.metadata.setdefault("kernelspec", dict(KERNELSPEC))
    nb.metadata.setdefault("language_info", dict(LANGUAGE_INFO))
    return nb
