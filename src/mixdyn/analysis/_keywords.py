"""The keyword spelling of an analysis: a name and keyword options, turned into the analysis
value in one place.

The studies (:func:`~mixdyn.sweep`, :func:`~mixdyn.differentiable`, :func:`~mixdyn.fit`,
:func:`~mixdyn.optimize`) take an analysis value; their spelling ``analysis="forward",
rtol=1e-10`` is deprecated and read here (:func:`study_analysis`: a DeprecationWarning names
the value to give). The model-file layer reads its runs' settings here
(:func:`from_keywords`, :func:`member_values`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence

from ..errors import ModelError
from ._options import suggestions
from ._setup import Analysis
from .forward import Forward
from .inverse import Inverse
from .kinematic import Kinematic
from .mixed import Mixed
from .statics import QuasiStatic

#: The analyses of the keyword spelling, by name (``"statics"``: the quasi-static analysis,
#: an equilibrium per output time).
NAMES: dict[str, type[Analysis]] = {
    "forward": Forward,
    "mixed": Mixed,
    "kinematic": Kinematic,
    "inverse": Inverse,
    "statics": QuasiStatic,
}


def analysis_class(name) -> type[Analysis]:
    """The analysis class of a name of the keyword spelling.

    Raises:
        ModelError: an unknown name (with the close matches).
    """
    if isinstance(name, str) and name in NAMES:
        return NAMES[name]
    close = suggestions(str(name), NAMES)
    hint = f"did you mean {' or '.join(close)}? " if close else ""
    raise ModelError(
        f"unknown analysis {name!r}; {hint}give an analysis value of mixdyn.analyses "
        "(Forward(...), Mixed(...), Kinematic(...), Inverse(...), QuasiStatic(...))",
        "analysis",
    )


def from_keywords(name: str, t, kwargs: dict) -> tuple[Analysis, dict | None]:
    """The analysis ``name`` with the keyword options ``kwargs`` as its value, and the
    integrator options its results record (None: the value's own).

    Args:
        name: a key of :data:`NAMES`.
        t: (N,) the output times [time] (a forward or mixed method's step count is checked
            against them).
        kwargs: the analysis function's keywords (``prepared`` is left out: each run makes
            its own start).

    Raises:
        ModelError: an unknown name or option, or a bad value.
    """
    return analysis_class(name)._from_keywords(t, dict(kwargs))


def member_values(
    name: str,
    t,
    kwargs: Sequence[dict],
    describe: Callable[[int], str] = lambda i: "",
    offset: int = 0,
) -> tuple[list[Analysis], list[dict | None]]:
    """The analysis values of a sweep's members given by keywords (the model-file layer's
    members, whose settings may differ), and the integrator options each result records
    (:func:`from_keywords`); keywords given as one object for several members are read
    once.

    Args:
        name: a key of :data:`NAMES`.
        t: (N,) the output times [time].
        kwargs: per member, the analysis function's keywords.
        describe: member index -> words naming it in an error (its varied values).
        offset: the sweep's index of the first member (a chunk of a larger sweep).

    Raises:
        ModelError: an unknown option or a bad value, with a note naming the member.
    """
    read: dict[int, tuple[Analysis, dict | None]] = {}
    values, records = [], []
    for i, kw in enumerate(kwargs):
        if id(kw) not in read:
            try:
                read[id(kw)] = from_keywords(name, t, kw)
            except ModelError as err:
                err.add_note(f"in member {offset + i} of the sweep{describe(i)}")
                raise
        value, record = read[id(kw)]
        values.append(value)
        records.append(record)
    return values, records


def study_analysis(study: str, analysis, t, kwargs: dict) -> tuple[Analysis, dict | None]:
    """The analysis value a study runs, and the integrator options its results record.

    Args:
        study: the study's function, for the messages (``"md.sweep"``).
        analysis: an analysis value; or, deprecated, an analysis' name (or None:
            ``"forward"``) with its keyword options in ``kwargs``.
        t: (N,) the output times [time].
        kwargs: the study's keyword options of the analysis (deprecated).

    Returns:
        ``(value, recorded)``: ``Forward()`` for no analysis and no keywords.

    Raises:
        ModelError: an analysis value together with keyword options, or an unknown name or
            option (:func:`from_keywords`).
    """
    if isinstance(analysis, Analysis):
        if kwargs:
            name = type(analysis).__name__
            raise ModelError(
                f"analysis is a {name} value, which holds the analysis' options: give "
                f"{', '.join(kwargs)} in it ({name}({', '.join(f'{k}=...' for k in kwargs)})), "
                f"not as keywords of {study}",
                ", ".join(kwargs),
            )
        return analysis, None
    if analysis is None and not kwargs:
        return Forward(), None
    name = "forward" if analysis is None else analysis
    cls = analysis_class(name)
    spelled = ", ".join([*([f"analysis={name!r}"] if analysis is not None else []),
                         *(f"{k}=..." for k in kwargs)])  # fmt: skip
    warnings.warn(
        f"{study}(..., {spelled}) is deprecated: give the analysis as a value, "
        f"{study}(..., analysis={cls._spelling(kwargs)})",
        DeprecationWarning,
        stacklevel=3,
    )
    return from_keywords(name, t, kwargs)


__all__ = ["NAMES", "analysis_class", "from_keywords", "member_values", "study_analysis"]
