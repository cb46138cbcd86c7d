"""The sidebar's navigation tree without copying every page's whole table of contents.

Furo asks Sphinx, for each of the site's pages, for the global toctree with
``titles_only=True``: every page's title with its sub-toctrees, nothing below. Sphinx
(``sphinx.environment.adapters.toctree``) first copies each listed page's whole table of
contents (an API page's holds an entry per documented object) and only then deletes
everything but the top-level titles and the sub-toctrees; that copying was most of the
HTML writing phase. Here a listed page's entry, as that copy-then-delete leaves it, is
made once per (page, title, depth limit, whether the page is an ancestor of the one being
written, ...) and each page gets a deep copy of it: the HTML is the same byte for byte,
only the work is not repeated. Calls without ``titles_only`` are Sphinx's own.
"""

from __future__ import annotations

import contextvars

from sphinx import addnodes
from sphinx.environment.adapters import toctree as _toctree

#: True while Sphinx resolves a toctree with ``titles_only`` (set by :func:`_entries`).
_TITLES_ONLY = contextvars.ContextVar("bvpnav_titles_only", default=False)

_sphinx_entries = _toctree._entries_from_toctree
_sphinx_standard_entry = _toctree._toctree_standard_entry


def _titles_only(toc):
    """What Sphinx's ``_entries_from_toctree`` keeps of an entry with ``titles_only``: each
    top-level item's title and the sub-toctrees below it (the same statements)."""
    for top_level in toc.children:
        if len(top_level) > 1:
            if subtrees := list(top_level.findall(addnodes.toctree)):
                top_level[1][:] = subtrees
            else:
                top_level.pop(1)
    return toc


def _entries(env, prune, titles_only, *args, **kwargs):
    token = _TITLES_ONLY.set(bool(titles_only))
    try:
        return _sphinx_entries(env, prune, titles_only, *args, **kwargs)
    finally:
        _TITLES_ONLY.reset(token)


def _standard_entry(title, ref, maxdepth, toc, toctree_ancestors, prune, collapse, tags):
    if not _TITLES_ONLY.get():
        return _sphinx_standard_entry(title, ref, maxdepth, toc, toctree_ancestors, prune, collapse, tags)
    cache = _standard_entry.cache
    # the arguments Sphinx's entry depends on; ``toc`` by identity (a page read again has a new one)
    key = (title, ref, maxdepth, ref in toctree_ancestors, prune, collapse, id(tags), id(toc))
    hit = cache.get(key)   # the entry keeps toc and tags alive, so their ids cannot be reused
    if hit is None:
        entry, refdoc = _sphinx_standard_entry(title, ref, maxdepth, toc, toctree_ancestors, prune,
                                               collapse, tags)
        hit = cache[key] = (toc, tags, _titles_only(entry), refdoc)
    return hit[2].deepcopy(), hit[3]


_standard_entry.cache = {}


def setup(app):
    _toctree._entries_from_toctree = _entries
    _toctree._toctree_standard_entry = _standard_entry
    app.connect("env-before-read-docs", lambda *_: _standard_entry.cache.clear())
    return {"parallel_read_safe": True, "parallel_write_safe": True}
