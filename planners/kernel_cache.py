"""Keep the planners' numba cache consistent with their sources.

numba's cache (``cache=True``) checks only the source file of the kernel it loads: after
an edit of ``swing.py``, a kernel in ``lattice_kernel.py`` that calls ``adjust_one``
still loads its cached machine code with the old ``adjust_one`` compiled in. Before any
kernel is loaded, :func:`refresh` (called by ``planners/__init__.py``) compares a hash of
every ``planners/*.py`` with the one stored next to the cache and, where they differ (or
none is stored), deletes the package's cache files (``*.nbi``, ``*.nbc``), so every
kernel compiles afresh once. Imports nothing but the standard library and numba.

Two processes importing planners at once right after an edit may both clear the cache
(each then compiles what it uses): the cost of a compile, not a wrong kernel.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

__all__ = ["PACKAGE", "STAMP", "cache_dir", "refresh", "sources_digest"]

#: The planners package directory.
PACKAGE = Path(__file__).resolve().parent
#: Name of the file holding the sources' hash in the cache directory.
STAMP = "planners-sources.sha256"


def sources_digest(package: Path = PACKAGE) -> str:
    """SHA-256 (hex) of the names and contents of the ``*.py`` files in ``package``."""
    h = hashlib.sha256()
    for path in sorted(package.glob("*.py")):
        h.update(path.name.encode() + b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


def _probe() -> None:
    """A function for numba's cache locators (they read only its first line number)."""


def cache_dir(package: Path = PACKAGE) -> Path | None:
    """The directory numba caches the kernels of modules in ``package`` in (the first
    of its locators that applies: ``NUMBA_CACHE_DIR``, the package's ``__pycache__``,
    the user-wide cache), or None where none applies."""
    from numba.core import caching

    impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl
    source = str(next(iter(sorted(package.glob("*.py"))), package / "__init__.py"))
    for cls in impl._locator_classes:
        try:
            locator = cls.from_function(_probe, source)
        except Exception:  # a locator for other kinds of source (IPython, zip)
            continue
        if locator is not None:
            return Path(locator.get_cache_path())
    return None


def refresh(package: Path = PACKAGE, directory: Path | None = None) -> bool:
    """Delete the numba cache files (``*.nbi``, ``*.nbc``) in ``directory`` (default
    :func:`cache_dir` of ``package``) unless the hash of ``package``'s sources stored
    there (:data:`STAMP`) is the current one; then store the current one. Returns
    whether it cleared the cache. Does nothing where the directory cannot be written
    (numba does not cache there either)."""
    directory = cache_dir(package) if directory is None else directory
    if directory is None:
        return False
    digest = sources_digest(package)
    stamp = directory / STAMP
    try:
        if stamp.read_text().strip() == digest:
            return False
    except OSError:
        pass
    try:
        directory.mkdir(parents=True, exist_ok=True)
        for path in directory.iterdir():
            if path.suffix in (".nbi", ".nbc"):
                path.unlink(missing_ok=True)
        tmp = directory / f"{STAMP}.{os.getpid()}"
        tmp.write_text(digest + "\n")
        os.replace(tmp, stamp)
    except OSError:
        return False
    return True
