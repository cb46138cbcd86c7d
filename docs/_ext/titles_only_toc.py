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

A page that no toctree lists (the highlighted sources, the general index, the search page)
gets the same sidebar as every other such page in its folder: Sphinx's tree depends on the
page only through its ancestors in the toctrees (none), the entries that point at it (none)
and the links relative to its folder. Such a page's tree is made once per folder (and
arguments); the listed pages' are made for each page, as Sphinx does.
"""

from __future__ import annotations

import contextvars
import posixpath

from sphinx import addnodes
from sphinx.builders.html import StandaloneHTMLBuilder
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

_sphinx_local_toctree = StandaloneHTMLBuilder._get_local_toctree


def _listed(env) -> set[str]:
    """The pages a toctree lists, those holding a toctree and the root page."""
    listed = {env.config.root_doc, *env.toctree_includes}
    for children in env.toctree_includes.values():
        listed.update(children)
    return listed


def _local_toctree(self, docname, collapse=True, **kwargs):
    # links relative to the folder: the html builder's "page.html" targets (not dirhtml's)
    if docname in _listed(self.env) or type(self).get_target_uri is not StandaloneHTMLBuilder.get_target_uri:
        return _sphinx_local_toctree(self, docname, collapse, **kwargs)
    key = (id(self), posixpath.dirname(docname), collapse, tuple(sorted(kwargs.items())))
    cache = _local_toctree.cache
    if key not in cache:
        cache[key] = _sphinx_local_toctree(self, docname, collapse, **kwargs)
    return cache[key]


_local_toctree.cache = {}


def _clear(*_):
    _standard_entry.cache.clear()
    _local_toctree.cache.clear()


def setup(app):
    _toctree._entries_from_toctree = _entries
    _toctree._toctree_standard_entry = _standard_entry
    StandaloneHTMLBuilder._get_local_toctree = _local_toctree
    app.connect("env-before-read-docs", _clear)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
