"""Checks of the numbers given to the model's constructors: finite, and in range.

Values being traced by JAX (inside a transformation) are not concrete and pass unchecked.
"""

from __future__ import annotations

import jax
import numpy as np

from ..errors import ModelError


def _traced(value) -> bool:
    leaves = jax.tree_util.tree_leaves(value)
    return any(isinstance(x, jax.core.Tracer) for x in leaves)


def finite(
    value,
    what: str,
    element: str | None = None,
    *,
    above=None,
    at_least=None,
    field: str | None = None,
) -> None:
    """Raise a :class:`ModelError` unless every entry of ``value`` is a finite number (and
    ``> above`` / ``>= at_least`` where given).

    Args:
        value: a number or an array of numbers.
        what: what the value is, for the message (``"length"``).
        element: the element's name, for the message.
        above: a strict lower bound, or None.
        at_least: a lower bound, or None.
        field: the element's field that holds the value, or None (the error's ``field``:
            a model file reports it at that field's line).
    """
    if _traced(value):
        return
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"{what} must be a number, got {value!r}", element, field=field) from None
    shown = f"{float(a.ravel()[0]):g}" if a.size == 1 else str(a.tolist())
    if not np.all(np.isfinite(a)):
        raise ModelError(f"{what} must be finite, got {shown}", element, field=field)
    if above == 0 and not np.all(a > 0):
        raise ModelError(f"{what} {shown} is not positive; it must be > 0", element, field=field)
    if above is not None and not np.all(a > above):
        raise ModelError(f"{what} must be > {above:g}, got {shown}", element, field=field)
    if at_least is not None and not np.all(a >= at_least):
        raise ModelError(f"{what} must be >= {at_least:g}, got {shown}", element, field=field)


__all__ = ["finite"]
