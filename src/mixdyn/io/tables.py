"""Tables read from disk: a recording (an identify run's ``data``, CSV) and written results
(``results.csv`` / ``results.parquet``, read by ``mixdyn plot`` and ``mixdyn animate
--results``).

Each file is checked before it is read: a regular file (a FIFO, a socket, a device or a
folder is refused at once instead of blocking), a recording of at most
:data:`MAX_DATA_BYTES` bytes; a file that is not UTF-8 CSV or not Parquet is a
:class:`~mixdyn.io.FileError` naming it.
"""

from __future__ import annotations

import io
import os
import stat

from ._errors import FileError

#: The largest recording an identify run reads [bytes]: 20 MB, about 400,000 rows of three
#: columns at full precision. Each of the fit's runs outputs every time of the recording, so
#: a larger one is better thinned first (every k-th row).
MAX_DATA_BYTES = 20_000_000


def read_bytes(path, *, limit: int | None = None, hint: str = "") -> bytes:
    """The bytes of the regular file ``path``, of at most ``limit`` bytes.

    The file is opened without blocking and checked before it is read: a FIFO, a socket, a
    device or a folder is refused at once (never waited on), a file over ``limit`` before a
    byte is read.

    Args:
        path: the file.
        limit: the largest size accepted [bytes], or None (any).
        hint: what to do about a file over ``limit``.

    Raises:
        FileError: no such file, not a regular file, too large, or unreadable.
    """
    file = os.fspath(path)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(file, flags)
    except FileNotFoundError:
        raise FileError("no such file", file=file, hint="check the path") from None
    except IsADirectoryError:
        raise FileError("is a folder, not a file", file=file, hint="give a file") from None
    except OSError as e:
        raise FileError(f"cannot read the file ({e.strerror})", file=file) from None
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise FileError("is a folder, not a file", file=file, hint="give a file")
        if not stat.S_ISREG(st.st_mode):
            raise FileError(
                "is a pipe, socket or device, not a file",
                file=file,
                hint="give a file saved on disk",
            )
        if limit is not None and st.st_size > limit:
            raise FileError(
                f"the file has {st.st_size:,} bytes, more than the limit of {limit:,}",
                file=file,
                hint=hint,
            )
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        with os.fdopen(fd, "rb") as f:
            fd = -1
            return f.read() if limit is None else f.read(limit + 1)
    except OSError as e:
        raise FileError(f"cannot read the file ({e.strerror})", file=file) from None
    finally:
        if fd >= 0:
            os.close(fd)


def read_csv(path, *, limit: int | None = None, hint: str = ""):
    """The CSV file ``path`` (UTF-8, a header line of column names) as a pandas DataFrame.

    Args:
        path: the file.
        limit: the largest size accepted [bytes], or None (any).
        hint: what to do about a file over ``limit``.

    Raises:
        FileError: as :func:`read_bytes`, or not UTF-8 text, or not CSV.
    """
    import pandas as pd

    file = os.fspath(path)
    raw = read_bytes(file, limit=limit, hint=hint)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise FileError(
            f"is not UTF-8 text (byte {e.start}), hence not CSV",
            file=file,
            hint="give a CSV file saved as UTF-8",
        ) from None
    try:
        return pd.read_csv(io.StringIO(text))
    except (ValueError, pd.errors.ParserError, pd.errors.EmptyDataError) as e:
        problem = " ".join(str(e).split()) or type(e).__name__
        raise FileError(f"cannot be read as CSV ({problem})", file=file) from None


def read_parquet(path):
    """The Parquet file ``path`` as a pandas DataFrame (pyarrow reads it).

    Raises:
        FileError: as :func:`read_bytes`, pyarrow not installed, or not a Parquet file.
    """
    file = os.fspath(path)
    raw = read_bytes(file)
    papq = parquet_module(file, "reading")
    try:
        return papq.read_table(io.BytesIO(raw)).to_pandas()
    except Exception as e:  # pyarrow's errors (ArrowInvalid, OSError...) share no base
        problem = " ".join(str(e).split()) or type(e).__name__
        raise FileError(
            f"is not a Parquet file ({problem})", file=file, hint="give a .parquet or a .csv"
        ) from None


def _optional(name: str, needs: str, install: str, file, option, instead: str | None):
    """The module ``name``, or the :class:`~mixdyn.io.FileError` saying ``needs`` (``"reading
    Parquet needs pyarrow"``) and how to get it: ``install``, or else ``instead`` (leaving
    ``option`` out where the command line asked for it)."""
    try:
        return __import__(name, fromlist=["_"])  # the module itself, not its package
    except ImportError:
        instead = f"leave {option} out" if option else instead
        raise FileError(
            f"{needs}, which is not installed",
            option,
            file=str(file),
            hint=install + (f" (or {instead})" if instead else ""),
        ) from None


def parquet_module(file, doing: str, option: str | None = None):
    """``pyarrow.parquet``, or the :class:`~mixdyn.io.FileError` saying it is missing.

    Args:
        file: the file read or written (or the model file), for the message.
        doing: ``"reading"`` or ``"writing"``, for the message.
        option: the command-line option asking for Parquet (``"--parquet"``), if any.
    """
    needs = f"{doing} Parquet needs pyarrow"
    return _optional("pyarrow.parquet", needs, "pip install pyarrow", file, option, "use the CSV")


def excel_module(file, doing: str, option: str | None = None):
    """``openpyxl`` (what pandas writes and reads ``.xlsx`` with), or the
    :class:`~mixdyn.io.FileError` saying it is missing.

    Args:
        file: the file read or written (or the model file), for the message.
        doing: ``"writing"`` or ``"reading"``, for the message.
        option: the command-line option asking for Excel (``"--excel"``), if any.
    """
    needs = f"{doing} Excel needs openpyxl"
    return _optional("openpyxl", needs, 'pip install "mixdyn[excel]"', file, option, None)


def require_numbers(table, columns, file, option: str) -> None:
    """Refuse a column of ``table`` among ``columns`` that holds text instead of numbers.

    Args:
        table: a pandas DataFrame.
        columns: the columns that must be numeric.
        file: where the table was read, for the message.
        option: the option (or field) naming the columns, for the message.

    Raises:
        FileError: the first column that is not numeric, with a value it holds.
    """
    import pandas as pd

    for c in columns:
        col = table[c]
        if pd.api.types.is_numeric_dtype(col) and not pd.api.types.is_bool_dtype(col):
            continue
        values = pd.to_numeric(col, errors="coerce")
        bad = col[values.isna() & col.notna()]
        sample = f" ({bad.iloc[0]!r} in data row {int(bad.index[0]) + 1})" if len(bad) else ""
        raise FileError(
            f"column {c!r} holds text, not numbers{sample}",
            option,
            file=str(file),
            hint="plot a numeric column (the first line of results.csv lists them all)",
        )


__all__ = [
    "MAX_DATA_BYTES",
    "excel_module",
    "parquet_module",
    "read_bytes",
    "read_csv",
    "read_parquet",
    "require_numbers",
]
