"""Results on disk: ``results.csv`` (or Parquet, or an Excel workbook) and ``meta.json`` per run.

``results.csv`` has a column ``t`` and every column of the :class:`mixdyn.Result` (body
coordinates ``{body}.x`` ..., reactions ``{joint}.Fx`` ..., driver efforts and unknown forces by
name, energies), in the file's ``output_units`` (else the model's units), at full precision.
Each header names its column and unit, ``name [unit]`` (``t [s]``, ``crank.phi [deg]``,
``motor [N·m]``; a column without unit by its name alone); :func:`read_table` reads them back
as names and units. ``results.parquet`` carries the units in its schema metadata
(:data:`PARQUET_KEY`). ``results.xlsx`` (openpyxl) holds the same table with the same
headers in a sheet ``results`` and ``meta.json``'s entries in a sheet ``meta``
(:func:`write_workbook`). ``meta.json`` holds the unit of every column, the run's settings
(solver, tolerances), the solver's counters and the mixdyn version. Units are engineering
labels (:func:`mixdyn.units.engineering`), which :mod:`mixdyn.units` reads back. A run with
rigid contacts also writes ``impacts.csv``: a row per impact, in the order resolved, with its
time, contact, impulses and velocities (:meth:`mixdyn.Result.impacts`), in the same units.
"""

from __future__ import annotations

import datetime
import io
import json
import math
import os
import pathlib
import re
from typing import Any

import numpy as np

from ..analysis import Result
from ..analysis.result import in_units, point_columns
from ..errors import NumericalError
from ..units import engineering

RESULTS_CSV = "results.csv"
RESULTS_PARQUET = "results.parquet"
RESULTS_XLSX = "results.xlsx"
META_JSON = "meta.json"
IMPACTS_CSV = "impacts.csv"


def jsonable(value: Any) -> Any:
    """``value`` with numpy scalars and arrays, tuples and odd floats made JSON-friendly."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        return jsonable(value.item())
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, str | int | bool) or value is None:
        return value
    try:
        return jsonable(np.asarray(value).tolist())
    except Exception:
        return str(value)


def write_result(
    result: Result,
    folder,
    *,
    parquet: bool = False,
    excel: bool = False,
    settings: dict | None = None,
    extra: dict | None = None,
    output_units: dict | None = None,
    points=(),
) -> list[pathlib.Path]:
    """Write ``result`` to ``folder/results.csv`` (and ``.parquet``, ``.xlsx``) and
    ``folder/meta.json``.

    Args:
        result: the analysis result.
        folder: the output folder (created).
        parquet: also write ``results.parquet``.
        excel: also write ``results.xlsx`` (:func:`write_workbook`; needs openpyxl).
        settings: the run's settings (analysis kind, solver, tolerances...) for ``meta.json``.
        extra: further entries of ``meta.json``.
        output_units: kind -> unit for the written columns (:func:`in_units`; default: the
            result's ``output_units``, else the model's units).
        points: point references (``"coupler.P"``) whose position, velocity and acceleration
            are written too (columns ``coupler.P.x``, ``.vx``, ``.ax`` and y).

    Returns:
        The files written.
    """
    from .._version import __version__

    folder = pathlib.Path(folder)
    if output_units is None:
        output_units = result.output_units
    cols, units = in_units(result, *point_columns(result, points), output_units)
    units = {c: engineering(u) for c, u in units.items()}
    names = list(cols)
    table = np.column_stack([np.asarray(cols[n]) for n in names]) if names else np.zeros((0, 0))
    _refuse_non_finite(table, names)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    csv = folder / RESULTS_CSV
    _write_csv(csv, headers(names, units), table)
    written.append(csv)
    if parquet:
        pq = folder / RESULTS_PARQUET
        import pandas as pd

        _write_parquet(pd.DataFrame(cols), pq, units, _unit_system(result.model.units))
        written.append(pq)
    meta = {
        "mixdyn_version": __version__,
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "model": result.model.name,
        "kind": result.kind,
        "unit_system": {
            "length": result.model.units.length,
            "mass": result.model.units.mass,
            "time": result.model.units.time,
            "angle": "rad",
        },
        "rows": len(table),
        "columns": names,
        "units": {c: units.get(c, "") for c in names},
        "output_units": dict(output_units or {}),
        "settings": jsonable(settings or {}),
        "stats": jsonable(result.stats),
        "status": "ok",
    }
    written.append(write_meta(folder, meta, extra))
    if "impacts" in result.stats:
        written.append(_write_impacts(folder / IMPACTS_CSV, result, output_units))
    if excel:
        import pandas as pd

        frame = pd.DataFrame(table, columns=headers(names, units))
        written.append(write_workbook(folder / RESULTS_XLSX, {"results": frame}, meta))
    return written


def write_excel(result: Result, path, *, points=(), output_units: dict | None = None):
    """Write ``result`` as an Excel workbook at ``path``: a sheet ``results`` with the
    columns of ``results.csv`` (``t`` first, headers ``name [unit]``) and a sheet ``meta``
    (the units of the columns, the model's unit system, the solver's counters), as
    :func:`write_workbook` writes them. Needs openpyxl (``pip install "mixdyn[excel]"``).

    Args:
        result: the analysis result.
        path: the workbook to write (``.xlsx``).
        points: point references whose columns are written too (``coupler.P.x``...).
        output_units: kind -> unit of the columns (default: the result's ``output_units``,
            else the model's units).

    Returns:
        The workbook's path.

    Raises:
        FileError: openpyxl is not installed.
        NumericalError: a column holds a NaN or an infinity (nothing is written).
    """
    import pandas as pd

    from .._version import __version__
    from .tables import excel_module

    path = pathlib.Path(path)
    excel_module(path, "writing")
    if output_units is None:
        output_units = result.output_units
    cols, units = in_units(result, *point_columns(result, points), output_units)
    units = {c: engineering(u) for c, u in units.items()}
    names = list(cols)
    table = np.column_stack([np.asarray(cols[n]) for n in names])
    _refuse_non_finite(table, names)
    meta = {
        "mixdyn_version": __version__,
        "model": result.model.name,
        "kind": result.kind,
        "unit_system": _unit_system(result.model.units),
        "rows": len(table),
        "units": {c: units.get(c, "") for c in names},
        "output_units": dict(output_units or {}),
        "stats": jsonable(result.stats),
    }
    frame = pd.DataFrame(table, columns=headers(names, units))
    return write_workbook(path, {"results": frame}, meta)


#: The most rows an Excel sheet holds, its header row included (Excel's own limit).
EXCEL_ROWS = 1_048_576


def write_workbook(path: pathlib.Path, sheets: dict, meta: dict) -> pathlib.Path:
    """An Excel workbook (``.xlsx``, written by pandas through openpyxl) at ``path``, whole
    or not at all (through a temporary file replaced at the end).

    Args:
        path: the workbook.
        sheets: sheet name -> pandas DataFrame, headers ``name [unit]`` (:func:`headers`);
            each a sheet, in order, without an index column. Numbers are written with 16
            significant digits (openpyxl's format: within 5e-16 of the double's value,
            relative); a NaN (a failed sweep member's summary) is an empty cell.
        meta: the run's ``meta.json`` entries: the last sheet, ``meta``, a row per entry
            (``entry``, ``value``; nested entries as ``units.motor``, lists as JSON text).

    Raises:
        FileError: openpyxl is not installed, or a sheet has more rows than Excel holds
            (:data:`EXCEL_ROWS`).
    """
    import pandas as pd

    from ._errors import FileError
    from .tables import excel_module

    excel_module(path, "writing")
    for name, df in sheets.items():
        if len(df) + 1 > EXCEL_ROWS:
            raise FileError(
                f"sheet {name!r} has {len(df):,} rows, more than Excel holds ({EXCEL_ROWS - 1:,})",
                file=str(path),
                hint="write fewer output times, or use the CSV or --parquet",
            )
    rows = _flat(jsonable(meta))
    tmp = path.with_name(path.name + ".tmp")
    with pd.ExcelWriter(tmp, engine="openpyxl") as book:
        for name, df in sheets.items():
            df.to_excel(book, sheet_name=name, index=False)
        pd.DataFrame(rows, columns=["entry", "value"]).to_excel(
            book, sheet_name="meta", index=False
        )
    os.replace(tmp, path)
    return path


def _flat(meta: dict, prefix: str = "") -> list[tuple[str, object]]:
    """``meta``'s entries as ``(entry, value)`` rows: nested dicts as ``a.b``, lists as
    JSON text, numbers and text as they are."""
    rows = []
    for k, v in meta.items():
        if isinstance(v, dict):
            rows += _flat(v, f"{prefix}{k}.") if v else [(f"{prefix}{k}", "")]
        elif isinstance(v, list):
            rows.append((f"{prefix}{k}", json.dumps(v)))
        else:
            rows.append((f"{prefix}{k}", "" if v is None else v))
    return rows


def write_failure(
    error: NumericalError,
    folder,
    *,
    settings: dict | None = None,
    extra: dict | None = None,
    output_units: dict | None = None,
    model=None,
) -> list[pathlib.Path]:
    """Write what a failed run computed: ``folder/results.csv`` with the states up to the
    failure (the error's ``partial``, :class:`mixdyn.analysis.result.Partial`: ``t`` and
    the bodies' coordinates and velocities; no file where it has none) and
    ``folder/meta.json`` with ``status: failed`` and ``failure``: the time (in the model's
    time unit, named as ``time_unit``), the error's class, its message and the elements
    involved. ``model``: the run's model where the error carries no states.

    Returns:
        The files written.
    """
    from .._version import __version__

    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    partial = getattr(error, "partial", None)
    names, units = [], {}
    rows = 0
    if partial is not None and len(partial.t):
        cols, units = in_units(partial, partial.columns(), partial.units(), output_units)
        units = {c: engineering(u) for c, u in units.items()}
        names = list(cols)
        table = np.column_stack([np.asarray(cols[n]) for n in names])
        rows = len(table)
        csv = folder / RESULTS_CSV
        _write_csv(csv, headers(names, units), table)
        written.append(csv)
    model = getattr(partial, "model", None) or model
    meta = {
        "mixdyn_version": __version__,
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "model": None if model is None else model.name,
        "status": "failed",
        "failure": {
            "time": error.time,
            "time_unit": None if model is None else model.units.label("time"),
            "error": type(error).__name__,
            "cause": error.message,
            "elements": list(error.elements),
        },
        "unit_system": None if model is None else _unit_system(model.units),
        "rows": rows,
        "columns": names,
        "units": {c: units.get(c, "") for c in names},
        "output_units": dict(output_units or {}),
        "settings": jsonable(settings or {}),
    }
    written.append(write_meta(folder, meta, extra))
    return written


def write_meta(folder: pathlib.Path, meta: dict, extra=None) -> pathlib.Path:
    """``meta`` with ``extra``'s entries as ``folder/meta.json``, written whole or not at all
    (through a temporary file replaced at the end); returns its path."""
    meta.update(jsonable(extra or {}))
    path = folder / META_JSON
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(jsonable(meta), indent=2) + "\n", encoding="utf-8")
    os.replace(tmp, path)
    return path


def write_frame(df, path: pathlib.Path) -> pathlib.Path:
    """A pandas DataFrame to CSV at full precision, written whole or not at all (through a
    temporary file replaced at the end)."""
    tmp = path.with_suffix(".csv.tmp")
    df.to_csv(tmp, index=False, float_format="%.17g")
    os.replace(tmp, path)
    return path


#: The key of mixdyn's entry in a Parquet file's schema metadata (JSON: units, unit system).
PARQUET_KEY = b"mixdyn"


def _unit_system(units) -> dict:
    return {"length": units.length, "mass": units.mass, "time": units.time, "angle": "rad"}


def _write_parquet(df, path: pathlib.Path, units: dict, system: dict | None) -> None:
    """``df`` to Parquet with the columns' units and the unit system in the schema metadata
    (``PARQUET_KEY``), so that the file alone says what its numbers are."""
    from .tables import parquet_module

    papq = parquet_module(path, "writing")
    import pyarrow as pa

    table = pa.Table.from_pandas(df, preserve_index=False)
    entry = {"units": {c: units.get(c, "") for c in df.columns}, "unit_system": system}
    meta = dict(table.schema.metadata or {})
    meta[PARQUET_KEY] = json.dumps(jsonable(entry)).encode()
    papq.write_table(table.replace_schema_metadata(meta), path)


def parquet_units(path) -> dict:
    """The units a Parquet file written by mixdyn carries (``{}`` if none)."""
    from .tables import parquet_module

    try:
        meta = parquet_module(path, "reading").read_schema(path).metadata or {}
    except (OSError, ValueError):  # not Parquet (pyarrow's ArrowInvalid): no units
        return {}
    return json.loads(meta[PARQUET_KEY]).get("units", {}) if PARQUET_KEY in meta else {}


def headers(names, units: dict) -> list[str]:
    """The CSV headers of columns ``names``: ``name [unit]``, or the name alone where the
    column has no unit (a count, a ratio)."""
    return [f"{n} [{units[n]}]" if units.get(n) else n for n in names]


_HEADER = re.compile(r"^(?P<name>.*\S)\s+\[(?P<unit>[^\[\]]*)\]$")


def split_headers(columns) -> tuple[list[str], dict[str, str]]:
    """Column names and units of CSV headers written by :func:`headers` (``motor [N·m]`` ->
    ``motor``, ``N·m``); a header without ``[unit]`` is a name without unit (a table of plain
    names reads as it is)."""
    names, units = [], {}
    for text in columns:
        m = _HEADER.match(str(text))
        name = m["name"] if m else str(text)
        names.append(name)
        if m and m["unit"].strip():
            units[name] = m["unit"].strip()
    return names, units


def _write_csv(path: pathlib.Path, names: list[str], table: np.ndarray) -> None:
    """The table as CSV, as ``pandas.DataFrame.to_csv(index=False, float_format="%.17g")``
    writes it (names quoted where needed; every number at full precision), without pandas."""
    import csv

    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(names)
    if table.size:
        np.savetxt(buf, table, fmt="%.17g", delimiter=",")
    tmp = path.with_suffix(".csv.tmp")
    tmp.write_text(buf.getvalue(), encoding="utf-8")
    os.replace(tmp, path)


def _write_impacts(path: pathlib.Path, result: Result, output_units) -> pathlib.Path:
    """The run's impacts (:meth:`mixdyn.Result.impacts`) as CSV, headers ``name [unit]``,
    numbers at full precision."""
    df = result.impacts(output_units)
    df.columns = headers(list(df.columns), df.attrs["units"])
    tmp = path.with_suffix(".csv.tmp")
    df.to_csv(tmp, index=False, float_format="%.17g", lineterminator="\n")
    os.replace(tmp, path)
    return path


def _refuse_non_finite(table: np.ndarray, names: list[str]) -> None:
    """Raise a :class:`~mixdyn.NumericalError` (naming the column and time) rather than write
    a NaN or an infinity."""
    finite = np.isfinite(table)
    if finite.all():
        return
    row, col = np.argwhere(~finite)[0]
    t = float(table[row, names.index("t")]) if "t" in names else None
    raise NumericalError(
        f"column {names[col]!r} is not finite ({table[row, col]!r}); nothing was written",
        t,
    )


MEMBERS_CSV = "members.csv"
TABLE_CSV = "table.csv"
TABLE_PARQUET = "table.parquet"
SWEEP_NC = "sweep.nc"
SWEEP_XLSX = "sweep.xlsx"


def write_sweep(
    sweep,
    folder,
    *,
    parquet: bool = False,
    netcdf: bool = False,
    excel: bool = False,
    settings: dict | None = None,
    extra: dict | None = None,
) -> list[pathlib.Path]:
    """Write a sweep run's result (:class:`mixdyn.runs.sweep.FileSweep`) to ``folder``:
        ``members.csv`` (a row per member: index, varied values, status, error, summaries),
        ``table.csv`` (and ``table.parquet``: a row per member and output time), both with
        headers ``name [unit]`` as in ``results.csv`` (a column without a unit: its name), with
        ``netcdf`` ``sweep.nc`` (the table's columns as a labelled array on (member, t), the
        varied numbers and the status as coordinates, units in attributes; NetCDF 3 through
        SciPy), with ``excel`` ``sweep.xlsx`` (sheets ``members``, ``table`` and ``meta``, as
    :func:`write_workbook` writes them) and ``meta.json`` (units, settings, counts, timings).

        Returns:
            The files written.
    """
    from .._version import __version__

    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    model = next((r.model for r in sweep.sweep.results if r is not None), None)
    members = sweep.members()
    member_units = {c: engineering(u) for c, u in sweep.member_units().items()}
    named = dict(zip(members.columns, headers(list(members.columns), member_units), strict=True))
    members = members.rename(columns=named)
    written.append(write_frame(members, folder / MEMBERS_CSV))
    table = sweep.table()
    units = {c: engineering(u) for c, u in sweep.units.items()}
    named = dict(zip(table.columns, headers(list(table.columns), units), strict=True))
    written.append(write_frame(table.rename(columns=named), folder / TABLE_CSV))
    if parquet:
        path = folder / TABLE_PARQUET
        system = None if model is None else _unit_system(model.units)
        _write_parquet(table, path, units, system)
        written.append(path)
    if netcdf:
        path = folder / SWEEP_NC
        tmp = path.with_suffix(".nc.tmp")
        sweep.dataset().to_netcdf(tmp, engine="scipy")
        os.replace(tmp, path)
        written.append(path)
    meta = {
        "mixdyn_version": __version__,
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "kind": "sweep",
        "swept_run": sweep.plan.base.name,
        "members": sweep.plan.members,
        "failed": len(sweep.sweep.errors),
        "varied": list(sweep.plan.values),
        "unit_system": None
        if model is None
        else {
            "length": model.units.length,
            "mass": model.units.mass,
            "time": model.units.time,
            "angle": "rad",
        },
        "units": units,
        "rows": len(table),
        "seconds": sweep.seconds,
        "settings": jsonable(settings or {}),
        "status": "ok",
    }
    written.append(write_meta(folder, meta, extra))
    if excel:
        sheets = {"members": members, "table": table.rename(columns=named)}
        written.append(write_workbook(folder / SWEEP_XLSX, sheets, meta))
    return written


def read_result(path):
    """Read results written by :func:`write_result`.

    Args:
        path: the run's folder (a sweep's: its long table), or its ``results.csv`` /
            ``results.parquet`` (a sweep's ``table.csv`` / ``table.parquet``).

    Returns:
        ``(table, meta)``: a pandas DataFrame with a column ``t`` (also its unnamed index
        where the times do not repeat) and the columns by name (a CSV's ``name [unit]``
        headers split), and the ``meta.json`` dict (empty if
        absent). The units of the columns are in ``table.attrs["units"]``: the CSV headers',
        else ``meta.json``'s, else the Parquet file's.

    Raises:
        FileNotFoundError: no results there.
        FileError: a file that is not a regular file, not UTF-8 CSV or not Parquet, or
            Parquet without pyarrow installed.
    """
    from .tables import read_csv, read_parquet

    p = pathlib.Path(path)
    if p.is_dir():
        folder = p
        p = next(
            (
                folder / n
                for n in (RESULTS_PARQUET, TABLE_CSV, TABLE_PARQUET)
                if (folder / n).exists()
            ),
            folder / RESULTS_CSV,
        )
        if (folder / RESULTS_CSV).exists():
            p = folder / RESULTS_CSV
    else:
        folder = p.parent
    if not p.exists():
        raise FileNotFoundError(f"no results at {path} (expected {RESULTS_CSV} or a run folder)")
    df = read_parquet(p) if p.suffix == ".parquet" else read_csv(p)
    names, units = split_headers(df.columns)
    df.columns = names
    if "t" in names and df["t"].is_unique:  # the times also the index, as in Result.table()
        import pandas as pd

        df.index = pd.Index(df["t"].to_numpy())
    meta_path = folder / META_JSON
    meta = _read_meta(meta_path) if meta_path.exists() else {}
    if p.suffix == ".parquet":
        units = meta.get("units") or parquet_units(p)
    else:
        units = {**meta.get("units", {}), **units}
    df.attrs["units"] = {c: units[c] for c in names if units.get(c)}
    return df, meta


def read_table(path):
    """The table of results written by ``mixdyn run`` (or :func:`mixdyn.run_file`): a
    pandas DataFrame with a column ``t`` and every column by name, the units of the columns
    in ``df.attrs["units"]`` (from the CSV's ``name [unit]`` headers, or the Parquet file's
    metadata).

    Args:
        path: a run's folder, or its ``results.csv`` / ``results.parquet``; a sweep's
            folder or its ``table.csv`` / ``table.parquet`` (a row per member and time), or
            its ``members.csv`` (a row per member; no ``t``).

    Example::

        df = mixdyn.read_table("out/forward")
        df[["t", "crank.phi"]]; df.attrs["units"]["crank.phi"]  # 'deg'

    Raises:
        FileNotFoundError: no results there.
        FileError: as :func:`read_result`.
    """
    return read_result(path)[0]


def _read_meta(path: pathlib.Path) -> dict:
    """A run's ``meta.json``, or the :class:`~mixdyn.io.FileError` saying it is not JSON."""
    from ._errors import FileError
    from .tables import read_bytes

    try:
        meta = json.loads(read_bytes(path).decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise FileError(
            f"is not JSON ({e})", file=str(path), hint="write the run again, or remove it"
        ) from None
    if not isinstance(meta, dict):
        raise FileError("is not a JSON object", file=str(path), hint="write the run again")
    return meta


def read_motion(path, model, file) -> tuple[np.ndarray, np.ndarray]:
    """The motion of ``model`` in written results (``mixdyn animate --results``).

    Args:
        path: the run's folder, or its ``results.csv`` / ``results.parquet``.
        model: the model whose bodies' coordinates are read.
        file: the model file, for the messages.

    Returns:
        ``(t, q)``: (N,) times and (N, 3 * bodies) coordinates [model units].

    Raises:
        FileError: no results there, or results of another model (named as ``--results``).
    """
    from ._errors import FileError

    try:
        table, _ = read_result(path)
    except FileNotFoundError as e:
        raise FileError(str(e), "--results", file=str(file)) from None
    names = [f"{b.name}.{c}" for b in model.bodies for c in ("x", "y", "phi")]
    missing = [n for n in names if n not in table.columns]
    if missing:
        raise FileError(
            f"the results lack column {missing[0]!r}; they are not of this model",
            "--results",
            file=str(file),
            hint="give the results of this file's run",
        )
    return table["t"].to_numpy(), table[names].to_numpy()


def column_in_unit(table, units: dict, spec: str, source, k: int):
    """``table`` with the column of ``spec`` (``COLUMN=UNIT``) converted from its written unit
    (``units``: meta.json's, or the Parquet file's) into UNIT.

    Args:
        table: the results read (:func:`read_result`).
        units: the unit of each column.
        spec: ``COLUMN=UNIT`` as given on the command line (``--unit``).
        source: the results' path, for the message.
        k: the position of ``spec`` among the ``--unit`` options (from 0).

    Returns:
        ``(table, units)``: a copy of the table with the column converted, and the units.

    Raises:
        FileError: a unit of another dimension, an unknown column or unit, named as ``--unit``.
    """
    from ..units import SI
    from ._errors import FileError
    from .quantities import QuantityError, exponents, factor

    col, sep, target = spec.partition("=")
    col, target = col.strip(), target.strip()
    where = dict(file=str(source), hint="write --unit COLUMN=UNIT, e.g. crank.phi=deg")
    if not sep or not col or not target:
        raise FileError(f"{spec!r} is not COLUMN=UNIT", f"--unit {k + 1}", **where)
    if col not in table.columns:
        raise FileError(f"no column {col!r}", f"--unit {k + 1}", **where)
    was = units.get(col) or ""
    try:
        same = exponents(was or "1") == exponents(target)
        scale = factor(was or "1", None, SI) / factor(target, None, SI)
    except QuantityError as e:
        raise FileError(f"{target!r}: {e.problem}", f"--unit {k + 1}", **where) from None
    if not same:
        raise FileError(
            f"column {col!r} is in {was or 'no unit'}, which {target!r} is not a unit of",
            f"--unit {k + 1}",
            **where,
        )
    table = table.copy()
    table[col] = table[col] * scale
    return table, {**units, col: target}


def run_settings(spec) -> dict:
    """The settings of a run description worth recording (kind, solver, tolerances...)."""
    data = spec.model_dump(mode="json", exclude={"plots", "animation"})
    return data


__all__ = [
    "EXCEL_ROWS",
    "MEMBERS_CSV",
    "META_JSON",
    "RESULTS_CSV",
    "RESULTS_PARQUET",
    "RESULTS_XLSX",
    "SWEEP_XLSX",
    "TABLE_CSV",
    "TABLE_PARQUET",
    "column_in_unit",
    "headers",
    "in_units",
    "jsonable",
    "point_columns",
    "read_motion",
    "read_result",
    "read_table",
    "split_headers",
    "write_excel",
    "write_failure",
    "write_result",
    "write_sweep",
    "write_workbook",
]
