"""Files of the cache folder written atomically: a concurrent reader (another process
running the same model) sees a whole file or none. A folder that cannot be written is no
failure: the caller keeps what it made in memory."""

from __future__ import annotations

import contextlib
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
