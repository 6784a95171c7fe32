"""brdftab: tabulated BRDFs from Python, numpy arrays in and out.

Every function takes a SOURCE string, as the ``brdftab`` command line does: an analytic model
spec (inline JSON such as ``'{"model": "ggx", "alpha": 0.2}'`` or a ``.json`` file), a brdftab
table (``FILE.btdb`` or ``DB.btdb#NAME``), a MERL ``.binary`` or an RGL-EPFL ``.bsdf`` file.

Conventions (those of the library): local shading frame with z the surface normal, both
directions pointing away from the surface, ``wi`` towards the light and ``wo`` towards the
viewer; :meth:`Brdf.eval` returns f_r in 1/sr, not multiplied by a cosine; angles in radians.

>>> import numpy as np, brdftab
>>> b = brdftab.open('{"model": "lambert", "kd": 0.5}')
>>> b.eval([0, 0, 1], [0.3, 0, 1])
array([0.5, 0.5, 0.5], dtype=float32)

Errors of the library (missing file, unknown model, corrupt table) raise :class:`Error` with
the library's message; wrong arguments raise ``ValueError`` or ``TypeError``.
"""

from __future__ import annotations

import os as _os

from ._native import (  # noqa: F401
    Brdf,
    Error,
    Table,
    __version__,
    bake,
    bake_cached,
    check,
    convert,
    fit,
    info,
    open,
    rgb_basis,
)
from . import _native

__all__ = [
    "Brdf",
    "Database",
    "Error",
    "Table",
    "bake",
    "bake_cached",
    "check",
    "convert",
    "fit",
    "info",
    "open",
    "rgb_basis",
]


class Database:
    """A brdftab database: many named tables in one ``.btdb`` file. ``len(db)``, ``name in db``
    and ``for name in db`` are its tables' names (none for a file not created yet).

    >>> db = brdftab.Database("materials.btdb")            # doctest: +SKIP
    >>> db.add('{"model": "lambert", "kd": 0.5}', "matte")  # doctest: +SKIP
    >>> db.open("matte").eval([0, 0, 1], [0, 0, 1])          # doctest: +SKIP
    """

    def __init__(self, path):
        # A str, bytes or an os.PathLike of either, as every SOURCE and OUTPUT (str() of
        # anything else made a path of its repr: Database(b"m.btdb") wrote a file named
        # "b'm.btdb'"); kept as the str os.fsdecode gives (a name need not be UTF-8).
        self.path = _path_arg(path, "path")
        # The file, whatever the working directory becomes: what a pickled copy names (a
        # relative path failed in workers that run elsewhere: Dask, Ray, a spawned process
        # that changes directory) and what equality compares.
        self._abs = _os.path.abspath(self.path)

    def __repr__(self):
        return f"brdftab.Database({self.path!r})"

    def __reduce__(self):
        return (Database, (self._abs,))

    def __eq__(self, other):
        # A handle on a file: equal when the paths name it alike, made absolute and normalized
        # as os.path.abspath does ("./m.btdb" and "m.btdb"; a pickled copy too).
        if not isinstance(other, Database):
            return NotImplemented
        return self._abs == other._abs

    def __hash__(self):
        return hash((Database, self._abs))

    def names(self):
        """The table names, in file order (the table of contents; :meth:`info` reads each
        table)."""
        return _native.db_names(self.path)

    def _names(self):
        # A database that does not exist yet holds no table (``add`` creates it).
        if not _os.path.exists(self.path):
            return []
        return self.names()

    def __contains__(self, name):
        return name in self._names()

    def __len__(self):
        return len(self._names())

    def __iter__(self):
        # The names as the file holds them now: adding or removing tables while iterating
        # changes the file, not this list.
        return iter(self._names())

    def add(self, source, name, *, replace=False, **options):
        """Bakes SOURCE into table NAME (the database is created if absent); takes the keywords
        of :func:`bake`. Returns what ``brdftab info --json DB#NAME`` reports."""
        _check_name(name)
        return _native.bake(source, f"{self.path}#{name}", replace=replace, **options)

    def add_bytes(self, name, data, *, replace=False):
        """Adds the table in ``data`` — the bytes of a single-table ``.btdb`` file, as
        :func:`bake` writes one — as table NAME, copying its compressed chunks unchanged
        (checksums checked). This is how tables baked elsewhere (worker processes, other
        machines: see ``bindings/python/examples/dask_bake.py``) are gathered into one
        database; without ``replace`` an existing NAME is an error, so nothing is duplicated.

        ``bytes`` are read in place, without a copy; any other buffer (``bytearray``,
        ``memoryview``, ``mmap``) is copied into ``bytes`` first (MemoryError if that does not
        fit); anything else is a TypeError."""
        _check_name(name)
        if type(data) is not bytes:
            data = bytes(memoryview(data))
        _native.db_import(self.path, name, data, replace)

    def remove(self, name):
        """Removes table NAME; the database is rewritten atomically, after waiting for its lock
        with the GIL released (Ctrl-C stops the wait: ``KeyboardInterrupt``, the database as it
        was)."""
        _check_name(name)
        _native.db_remove(self.path, name)

    def rename(self, old, new):
        """Renames table OLD to NEW; the table keeps its place and its stored bytes. The
        database is rewritten atomically, after waiting for its lock with the GIL released
        (Ctrl-C stops the wait, as in :meth:`remove`).
        :class:`Error` (not found) when the database or OLD is absent; :class:`Error` when the
        database holds a table NEW already; ``ValueError`` for a name the rule refuses."""
        _check_name(old)
        _check_name(new)
        _native.db_rename(self.path, old, new)

    def open(self, name, **options):
        """Opens table NAME as a :class:`Brdf` (keywords of :func:`open`)."""
        _check_name(name)
        return _native.open(f"{self.path}#{name}", **options)

    def source(self, name):
        """The SOURCE string of table NAME (``DB#NAME``), e.g. for worker processes."""
        _check_name(name)
        return f"{self.path}#{name}"

    def info(self):
        """What ``brdftab info --json DB`` reports: the file and every table, read from their
        headers and indexes (no ``sampling_bytes`` for a database of several tables: that is
        ``info(db.source(name))``'s, one table's)."""
        return _native.info(self.path)


def _path_arg(path, what):
    """A path argument as the extension takes one — a str, bytes, or an os.PathLike of either —
    as the str ``os.fsdecode`` gives (bytes that are not UTF-8 held as surrogate escapes, which
    the extension encodes back to those bytes); anything else is a TypeError naming `what`."""
    if isinstance(path, (str, bytes, _os.PathLike)):
        return _os.fsdecode(_os.fspath(path))
    raise TypeError(
        f"{what}: expected a str, bytes or an os.PathLike, got {type(path).__name__}")


def _check_name(name):
    if not isinstance(name, str):
        raise TypeError(f"name: expected a string, got {type(name).__name__}")
    # The library's rule (non-empty; no '#', '/', '\\' or control characters): ValueError
    # naming `name`, in the words the CLI and the C ABI use.
    _native._check_table_name(name)
