"""numba's disk cache for RollBall's compiled code, kept honest across source changes.

numba keys a function's cached machine code to the source file the function is written in
(its modification time and size). The kernel's helpers are inlined into loops in other
files (the sweep loop in ``sweeps/kernel.py`` is built from ``kernel.py``'s steps), so a
change to ``kernel.py`` alone would leave those loops' cached code in use, stale. Here the
functions of every file in ``SOURCES`` are stamped with all of ``SOURCES`` at once: a change
to any of them recompiles all of them. numba's own places for the cache are kept (next to
the sources, ``NUMBA_CACHE_DIR``, or the user's cache folder); only the stamp is wider.
"""

from __future__ import annotations

import os
from pathlib import Path

from numba.core import caching

PACKAGE = Path(__file__).resolve().parent
SOURCES = tuple(PACKAGE / name for name in ("kernel.py", "sweeps/kernel.py"))   # all compiled code


def stamp() -> tuple:
    """What the cached code of every file in SOURCES is valid for: their times and sizes."""
    return tuple((st.st_mtime_ns, st.st_size) for st in map(os.stat, SOURCES))


class _KernelSources:
    """A locator for functions written in one of SOURCES, stamped with all of them."""

    @classmethod
    def from_function(cls, py_func, py_file):
        if Path(py_file).resolve() not in SOURCES:
            return None
        return super().from_function(py_func, py_file)

    def get_source_stamp(self):
        return stamp()


def _stamped(locator: type) -> type:
    return type(f"KernelSources{locator.__name__}", (_KernelSources, locator), {})


LOCATORS = tuple(_stamped(locator) for locator in (
    caching.UserProvidedCacheLocator, caching.InTreeCacheLocator, caching.UserWideCacheLocator))


def install() -> None:
    """Put the stamped locators first (each in front of numba's own of the same kind); once."""
    classes = caching.CacheImpl._locator_classes
    if not any(locator in classes for locator in LOCATORS):
        classes[:0] = LOCATORS
