"""Public names that moved to another module, still reached where they were, with a
DeprecationWarning that names the new spelling.

A module imports only the layers below it, so one whose names moved to a layer above it (the
model-file package :mod:`mixdyn.io`, whose ``Runner``, ``Plan`` and ``execute`` are
:mod:`mixdyn.runs`') cannot reach them itself: its ``__getattr__`` asks :func:`old_name`, and
the package above both, ``mixdyn/__init__.py`` (which every ``import mixdyn.X`` runs first),
says where each went (:func:`register`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

#: (module, name) -> (the new spelling, a function that returns the object).
_MOVED: dict[tuple[str, str], tuple[str, Callable[[], object]]] = {}


def register(module: str, name: str, new: str, reach: Callable[[], object]) -> None:
    """Say that ``module``'s public ``name`` is ``new`` (``"mixdyn.runs.Runner"``), the
    object ``reach()`` returns (it may import the layer above ``module``)."""
    _MOVED[module, name] = (new, reach)


def old_name(module: str, name: str):
    """``module.name`` by its old spelling: the object it moved to, with a DeprecationWarning
    that names the new spelling (for ``module``'s ``__getattr__``).

    Raises:
        AttributeError: ``module`` has no such name, moved or not.
    """
    try:
        new, reach = _MOVED[module, name]
    except KeyError:
        raise AttributeError(f"module {module!r} has no attribute {name!r}") from None
    warnings.warn(f"{module}.{name} is deprecated: use {new}", DeprecationWarning, stacklevel=3)
    return reach()
