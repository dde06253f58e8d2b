"""Files of the cache folder written atomically: a concurrent reader (another process
running the same model) sees a whole file or none. A folder that cannot be written is no
failure: the caller keeps what it made in memory."""

from __future__ import annotations

import contextlib
import functools
import os
import pathlib
import pickle
import tempfile


def _atomically(path: pathlib.Path, mode: str, write) -> None:
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-")
        with os.fdopen(fd, mode) as f:
            write(f)
        os.replace(tmp, path)
    except OSError:  # a read-only or full folder
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def write_pickle(path: pathlib.Path, obj) -> None:
    """Pickle ``obj`` to ``path`` atomically."""
    _atomically(path, "wb", lambda f: pickle.dump(obj, f, protocol=5))


def write_text(path: pathlib.Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    _atomically(path, "w", lambda f: f.write(text))


def write_bytes(path: pathlib.Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    _atomically(path, "wb", lambda f: f.write(data))


_installed: list = []


def atomic_jax_entries() -> bool:
    """Make JAX's persistent cache write its entries atomically.

    JAX's cache (``jax._src.lru_cache.LRUCache.put``) writes an entry with one ``write_bytes``:
    a second process reading it meanwhile (two runs of mixdyn at once, two test workers)
    gets a truncated entry, which JAX reports with a warning ("Error reading persistent
    compilation cache entry ... truncated stream", seen in CI) before compiling again, and an
    executable stored from it (:mod:`mixdyn._executables`) is damaged. Where JAX keeps no
    size limit (its default: no eviction, no lock, nothing else written) on a local folder,
    ``put`` now writes a temporary file and renames it into place; otherwise JAX's own
    ``put`` runs. Installed once; False where this JAX has no such class.
    """
    if _installed:
        return True
    try:
        from jax._src import lru_cache

        cls, suffix = lru_cache.LRUCache, lru_cache._CACHE_SUFFIX
        local = lru_cache._is_local_filesystem
        original = cls.put
    except (ImportError, AttributeError):
        return False

    @functools.wraps(original)
    def put(self, key: str, value: bytes) -> None:
        folder = os.fspath(getattr(self, "path", ""))
        if not key or getattr(self, "eviction_enabled", True) or not local(folder):
            return original(self, key, value)
        path = pathlib.Path(folder, f"{key}{suffix}")
        if not path.exists():
            write_bytes(path, value)

    cls.put = put
    _installed.append(original)
    return True
