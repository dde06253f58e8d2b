"""A run's one-page report (``report.html``): the mechanism drawn at the start, the run's
figures, each result column's range with its unit, the energy balance and the run's settings,
in one self-contained page (inline CSS, images as data URIs, no script, no network). A study's
page (a sweep, a fit, an optimization) adds its own tables (:class:`Table`: the varied values,
the numbers found with their units); a failed run's page states the failure first.

The drawing is SVG written here from the scene (no matplotlib); the figures are the files the
run has drawn already, read and inlined. Building a page costs a few milliseconds.
"""

from __future__ import annotations

import base64
import dataclasses
import json
import math
import pathlib
from html import escape

import numpy as np

from ._draw import COLORS

_MIME = {".png": "image/png", ".gif": "image/gif", ".svg": "image/svg+xml", ".jpg": "image/jpeg"}

_STYLE = """
body { font-family: system-ui, sans-serif; margin: 1.2em auto; padding: 0 1em; max-width: 1100px;
       color: #222; }
h1 { font-size: 1.35em; margin: 0 0 .3em; } h2 { font-size: 1.1em; margin: 1.2em 0 .4em; }
table { border-collapse: collapse; font-size: .9em; margin: .3em 0; }
th, td { border: 1px solid #ccc; padding: .15em .55em; text-align: left; }
td.n { text-align: right; font-variant-numeric: tabular-nums; }
th { background: #f2f2f2; }
.facts td:first-child { color: #555; }
figure { display: inline-block; margin: .4em .8em .4em 0; vertical-align: top; max-width: 48%; }
figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: .85em; color: #555; }
.drawing svg { border: 1px solid #ddd; background: #fff; max-width: 100%; height: auto; }
.ok { color: #1a7f37; } .bad { color: #b42318; }
p.failure { border: 1px solid #b42318; background: #fdecea; padding: .5em .8em; }
"""


# --------------------------------------------------------------------------- the drawing
def scene_svg(scene, frame: int = 0, width: int = 640) -> str:
    """The scene at ``frame`` as SVG text: guides, ground points, bodies (plates translucent,
    bars as thick lines), force symbols, pins, each body named; ``width`` [px], the height in
    the scene's proportions."""
    x0, x1, y0, y1 = scene.bounds
    k = width / max(x1 - x0, 1e-300)
    height = max(round((y1 - y0) * k), 60)

    def pt(p):
        return f"{(p[0] - x0) * k:.2f},{(y1 - p[1]) * k:.2f}"

    def d(points) -> str:
        out, up = [], True
        for p in np.asarray(points, dtype=float):
            if np.isnan(p[0]):
                up = True
                continue
            out.append(("M" if up else "L") + pt(p))
            up = False
        return "".join(out)

    parts = [
        f'<svg width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}" role="img" aria-label="the mechanism at the start">'
    ]
    for g in scene.guides:
        parts.append(f'<path d="{d(g)}" stroke="#999" stroke-dasharray="6 4" fill="none"/>')
    for p in scene.ground:
        x, y = (p[0] - x0) * k, (y1 - p[1]) * k
        parts.append(
            f'<path d="M{x:.2f},{y:.2f}l-7,12h14z" fill="#555"><title>ground</title></path>'
        )
    for b, (name, o) in enumerate(zip(scene.names, scene.outlines, strict=True)):
        color, o = COLORS[b % len(COLORS)], o[frame]
        if len(o) > 2:
            parts.append(
                f'<path class="body" d="{d(o)}Z" fill="{color}" fill-opacity="0.22" '
                f'stroke="{color}" stroke-width="2"><title>{escape(name)}</title></path>'
            )
        else:
            parts.append(
                f'<path class="body" d="{d(o)}" stroke="{color}" stroke-width="6" '
                f'stroke-linecap="round" fill="none"><title>{escape(name)}</title></path>'
            )
    for m in scene.symbols:
        parts.append(
            f'<path class="symbol" d="{d(m["path"][frame])}" stroke="{m["color"]}" '
            f'stroke-width="1.6" fill="none"><title>{escape(m["label"])}</title></path>'
        )
    for p in scene.pins[frame] if len(scene.pins) else ():
        x, y = (p[0] - x0) * k, (y1 - p[1]) * k
        parts.append(f'<circle cx="{x:.2f}" cy="{y:.2f}" r="4.5" fill="#fff" stroke="#000"/>')
    for b, (name, o) in enumerate(zip(scene.names, scene.outlines, strict=True)):
        c = np.mean(o[frame], axis=0)
        x, y = (c[0] - x0) * k, (y1 - c[1]) * k
        parts.append(
            f'<text x="{x + 6:.2f}" y="{y - 6:.2f}" font-size="12" font-weight="bold" '
            f'fill="{COLORS[b % len(COLORS)]}">{escape(name)}</text>'
        )
    parts.append("</svg>")
    return "".join(parts)


def start_drawing(result) -> str:
    """The mechanism of a :class:`mixdyn.Result` at its first output time as SVG text
    (:func:`scene_svg`, the forces' symbols included); a short note where it cannot be drawn
    (a drawing is a courtesy: the page's numbers still show)."""
    from .player import result_at
    from .scene import Scene

    try:
        q = np.asarray(result.q)[:1]
        return scene_svg(Scene(result.model, q, (), *result_at(result, [0])))
    except Exception as e:
        return f"<p>(no drawing: {escape(str(e))})</p>"


# --------------------------------------------------------------------------- numbers
def energy_balance(cols: dict, units: dict) -> list[tuple[str, float, str]] | None:
    """The energy balance of a dynamic run's columns (kinetic ``T``, potential ``V``, the
    non-conservative work ``Wn`` and the constraints' work ``Wc``): each at the end, the
    change of ``T + V`` and the balance's largest error ``max |T + V - (T0 + V0) - Wn - Wc|``,
    absolute and relative to the largest of the energies' ranges and the works. A run without
    work columns (an inverse run: its drivers' work is not among its columns) shows its
    energies without a balance.

    Returns:
        ``(what, value, unit)`` rows, or None where the columns have no energies.
    """
    need = ("energy.kinetic", "energy.potential")
    if any(c not in cols for c in need):
        return None
    T, V = (np.asarray(cols[c], dtype=float) for c in need)
    zero = np.zeros_like(T)
    Wn = np.asarray(cols.get("work.nonconservative", zero), dtype=float)
    Wc = np.asarray(cols.get("work.constraints", zero), dtype=float)
    bal = (T + V) - (T[0] + V[0]) - Wn - Wc
    scale = max(np.ptp(T), np.ptp(V), np.max(np.abs(Wn)), np.max(np.abs(Wc)), 1e-300)
    u = units.get("energy.kinetic", "")
    rows = [
        ("kinetic energy T at the start", float(T[0]), u),
        ("kinetic energy T at the end", float(T[-1]), u),
        ("potential energy V at the start", float(V[0]), u),
        ("potential energy V at the end", float(V[-1]), u),
        ("change of T + V", float(T[-1] + V[-1] - T[0] - V[0]), u),
    ]
    if "work.nonconservative" in cols:
        rows.append(("non-conservative work Wn (to the end)", float(Wn[-1]), u))
    if "work.constraints" in cols:
        rows.append(("constraints' work Wc (to the end)", float(Wc[-1]), u))
    if "work.nonconservative" not in cols and "work.constraints" not in cols:
        return rows  # no works to balance against
    rows += [
        ("largest balance error |T + V - (T0 + V0) - Wn - Wc|", float(np.max(np.abs(bal))), u),
        ("the same, relative to the largest range or work", float(np.max(np.abs(bal)) / scale), ""),
    ]
    return rows


def _num(v) -> str:
    v = float(v)
    return "nan" if math.isnan(v) else f"{v:.6g}"


def number(v) -> str:
    """A number as a report shows it: 6 significant digits (``nan`` for a NaN)."""
    return _num(v)


def _table(head: list[str], rows: list[list[str]], numeric=(), cls: str = "") -> str:
    th = "".join(f"<th>{escape(h)}</th>" for h in head) if any(head) else ""
    body = "".join(
        "<tr>"
        + "".join(
            f"<td{' class=n' if k in numeric else ''}>{escape(str(c))}</td>"
            for k, c in enumerate(r)
        )
        + "</tr>"
        for r in rows
    )
    thead = f"<thead><tr>{th}</tr></thead>" if th else ""
    return f'<table class="{cls}">{thead}<tbody>{body}</tbody></table>'


def _settings_rows(settings: dict, prefix: str = "") -> list[list[str]]:
    rows = []
    for k, v in settings.items():
        if v is None or v == [] or v == {}:
            continue
        if isinstance(v, dict):
            rows += _settings_rows(v, f"{prefix}{k}.")
        else:
            text = v if isinstance(v, str) else json.dumps(v)
            rows.append([f"{prefix}{k}", text if len(text) < 300 else text[:297] + "..."])
    return rows


def data_uri(path: pathlib.Path) -> str:
    """``data:`` URI of an image file (PNG, GIF, SVG, JPEG)."""
    mime = _MIME[path.suffix.lower()]
    return f"data:{mime};base64," + base64.b64encode(path.read_bytes()).decode("ascii")


# --------------------------------------------------------------------------- the page
@dataclasses.dataclass(frozen=True)
class Table:
    """A table of a report under its own heading.

    Attributes:
        heading: the section's heading.
        head: the column heads (a unit in its own column, or in the head as ``name [unit]``).
        rows: the rows, each a list of cells (text; numbers as :func:`number` writes them).
        numeric: the positions of the columns aligned as numbers.
        cls: the table's HTML class (what a test or a style finds it by).
    """

    heading: str
    head: list
    rows: list
    numeric: tuple = ()
    cls: str = ""

    def html(self) -> str:
        """The section's text: heading and table."""
        return f"<h2>{escape(self.heading)}</h2>" + _table(
            self.head, self.rows, numeric=self.numeric, cls=self.cls
        )


@dataclasses.dataclass
class Report:
    """What a run's report shows, gathered as the run is written; :meth:`write` reads the
    figures (drawn meanwhile) and writes the page.

    Attributes:
        path: the page to write (``report.html``).
        title: the page's heading.
        facts: ``(what, value)`` rows: the model, run, kind, rows, wall time...
        drawing: the mechanism as SVG text (:func:`scene_svg`), or "".
        figures: the run's figure and animation files, in order (those not written are left
            out: a run without figures).
        columns: the result columns as written (in the output units), name -> (N,); their
            ranges are shown under ``columns_heading`` (no section where empty).
        units: the columns' units.
        settings: the run's settings (nested dicts flattened to ``a.b`` rows).
        tables: a study's own tables (:class:`Table`), shown after the facts.
        failure: the failure a failed run ends with, one line shown first ("" where none).
        columns_heading: the heading of the columns' ranges.
    """

    path: pathlib.Path
    title: str
    facts: list
    drawing: str
    figures: list
    columns: dict
    units: dict
    settings: dict
    tables: list = dataclasses.field(default_factory=list)
    failure: str = ""
    columns_heading: str = "Result columns"

    def html(self) -> str:
        """The page's text."""
        cols, units = self.columns, self.units
        ranges = [
            [name, units.get(name, ""), _num(np.min(v)), _num(np.max(v))]
            for name, v in cols.items()
            if np.size(v)
        ]
        energy = energy_balance(cols, units)
        figures = []
        for f in self.figures:
            f = pathlib.Path(f)
            if f.suffix.lower() in _MIME and f.is_file():
                figures.append(
                    f'<figure><img src="{data_uri(f)}" alt="{escape(f.name)}">'
                    f"<figcaption>{escape(f.name)}</figcaption></figure>"
                )
        sections = [f"<h1>{escape(self.title)}</h1>"]
        if self.failure:
            sections.append(f'<p class="failure bad">{escape(self.failure)}</p>')
        sections.append(_table(["", ""], [[k, v] for k, v in self.facts], cls="facts"))
        sections += [t.html() for t in self.tables]
        if self.drawing:
            sections.append(f'<h2>The mechanism at the start</h2><div class="drawing">'
                            f"{self.drawing}</div>")  # fmt: skip
        if figures:
            sections.append('<h2>Figures</h2><div class="figures">' + "".join(figures) + "</div>")
        if ranges:
            sections.append(
                f"<h2>{escape(self.columns_heading)}</h2>"
                + _table(["column", "unit", "min", "max"], ranges, numeric=(2, 3), cls="ranges")
            )
        if energy is not None:
            sections.append(
                "<h2>Energy balance</h2>"
                + _table(
                    ["", "value", "unit"],
                    [[w, _num(v), u] for w, v, u in energy],
                    numeric=(1,),
                    cls="energy",
                )
            )
        sections.append(
            "<h2>Settings</h2>"
            + _table(["setting", "value"], _settings_rows(self.settings), cls="settings")
        )
        return (
            '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            '<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{escape(self.title)}</title><style>{_STYLE}</style></head><body>\n"
            + "\n".join(sections)
            + "\n</body></html>\n"
        )

    def write(self) -> pathlib.Path:
        """Write the page (atomically: a partial page is never left)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_suffix(".html.tmp")
        tmp.write_text(self.html(), encoding="utf-8")
        tmp.replace(self.path)
        return self.path


__all__ = [
    "Report",
    "Table",
    "data_uri",
    "energy_balance",
    "number",
    "scene_svg",
    "start_drawing",
]
