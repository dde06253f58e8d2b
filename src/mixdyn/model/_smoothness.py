"""Is a law smooth enough? Jumps in a law's value, slope or second derivative, found before
any computing.

A law whose value jumps moves a body by a finite distance in no time; one whose slope jumps
(a kink: piecewise linear segments, ``abs``) gives it an infinite acceleration. Neither can
be integrated, and the accelerations and forces an analysis reports would miss the jump's
impulse. One whose second derivative jumps (a constant-acceleration segment, a trapezoidal
speed) makes the accelerations and forces jump, finite, in no time (an infinite jerk): where
a run reports accelerations a law must be continuous with its second derivative, unless the
element accepts such jumps (``continuity: C1``). :func:`jumps` finds them on an interval (for
a cam, over its turn and across the wrap-around ``theta = 2 pi -> 0``), up to the ``order``
asked.

The law and its first three derivatives (exact, forward-mode AD) are sampled on a grid of
``n`` steps ``h``. Over a step ``[x_i, x_{i+1}]`` of a function ``g`` (the law, ``k = 0``,
its slope, ``k = 1``, or its second derivative, ``k = 2``) the trapezoidal rule of its
derivative, ``r = |g(x_{i+1}) - g(x_i) - h (g'(x_i) + g'(x_{i+1})) / 2|``, is small where
``g`` is smooth, at most about ``h |jump of g'| / 2`` where ``g'`` jumps (a jump one order
up), and the jump itself where ``g`` jumps (the sampled derivatives are one-sided, finite).
A step whose ``r`` is beyond what the derivatives sampled at its ends allow,

    k = 0:  r > h**2 (|f''_i| + |f''_{i+1}|) + h**3 (|f'''_i| + |f'''_{i+1}|) / 6 + floor
    k > 0:  r > h (|f'''_i| + |f'''_{i+1}|) + floor

(``f`` the law), is looked at ``n`` times closer, three times over (to ``h / n**3``): a jump
stays a jump at every scale, a steep smooth stretch resolves. What is left is a jump, placed
within ``h / n**3``; a jump of a lower order explains its share of the residual one order up
first (a jump in value before a kink, a kink before a jump of the second derivative). Jumps
smaller than ``rtol`` times the scale of their order (the law's range; its largest slope;
its largest second derivative) are left (rounded coefficients of segments that meet).

A piecewise polynomial (a spline, a Hermite motion) is read from its pieces instead: at each
break their values must meet, their slopes within a step's worth of their curvatures (and
their second derivatives within a step's worth of their third). A law smooth by its form to
the order asked (``Law.smooth_to``: a constant, polynomial or harmonic; an expression of
smooth terms) is not sampled over an interval, only across a turn's wrap-around. What is
found is kept by law and interval, so that models that share a law check it once.
"""

from __future__ import annotations

import dataclasses
import math
import re

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ..runtime._programs import cached_jit
from ._laws import PiecewisePolynomial
from ._validate import _traced

#: What a jump of each order does to what the law moves, in messages.
_EFFECT = (
    "would move in no time",
    "would change its speed in no time (an infinite acceleration)",
    "would change its acceleration in no time, and the accelerations and forces the run "
    "reports would jump with it",
)

#: A jump of each order, in messages.
_WHAT = ("value", "slope", "second derivative")

#: The continuity a law of a driver or a cam may be declared to have (its ``continuity``),
#: by the highest derivative that must be continuous.
CONTINUITY = {"C1": 1, "C2": 2}

#: The doc of the ``continuity`` of a driver's or a cam's law.
CONTINUITY_DOC = (
    "How smooth the law must be: ``C2`` (default: continuous with its slope and second "
    "derivative, as reported accelerations and forces need) or ``C1`` (the second "
    "derivative may jump: constant-acceleration segments, a trapezoidal speed)."
)


def check_continuity(value, element: str) -> None:
    """Refuse a ``continuity`` other than ``"C1"`` or ``"C2"`` (:data:`CONTINUITY`) of
    ``element``."""
    if value not in CONTINUITY:
        raise ModelError(
            f"continuity must be one of {', '.join(CONTINUITY)}, got {value!r}",
            element,
            field="continuity",
        )


@dataclasses.dataclass(frozen=True)
class Jump:
    """A jump of a law: ``order`` 0 in its value, 1 in its slope, 2 in its second
    derivative; ``at`` the place (in the law's variable, within ``resolution``), ``size`` its
    size (after minus before; the law's unit per the variable's unit**order); ``finite``
    False where the law or a derivative is not finite there (``size`` nan)."""

    order: int
    at: float
    size: float
    resolution: float
    finite: bool = True


def _samples(law, x: np.ndarray) -> np.ndarray:
    """``(4, len(x))``: the law and its first three derivatives at ``x`` (one compiled
    program per law's structure and grid size, kept between processes)."""
    return np.asarray(_derivatives(law, jnp.asarray(x, dtype=jnp.float64)), dtype=float).T


@cached_jit(optimize=False)  # runs once per law
def _derivatives(law, x):
    def derivs(s):
        def d1(u):
            return jax.jvp(law, (u,), (jnp.ones_like(u),))

        def d2(u):
            (f, fd), (_, fdd) = jax.jvp(d1, (u,), (jnp.ones_like(u),))
            return f, fd, fdd

        (f, fd, fdd), (_, _, fddd) = jax.jvp(d2, (s,), (jnp.ones_like(s),))
        return jnp.stack([f, fd, fdd, fddd])

    return jax.vmap(derivs)(x)


class _Turn(eqx.Module):
    """A law read within its period: ``law(start + (x - start) mod period)``."""

    law: object
    start: float
    period: float

    def __call__(self, x):
        return self.law(self.start + jnp.mod(x - self.start, self.period))


def _residuals(x: np.ndarray, d: np.ndarray, floors) -> tuple[np.ndarray, np.ndarray]:
    """Per step ``(len(floors), n)``: the residual ``r`` of the value, the slope (and the
    second derivative, for three floors), and what the derivatives at the step's ends
    allow."""
    h = np.diff(x)
    a = np.abs(np.nan_to_num(d, nan=0.0, posinf=0.0, neginf=0.0))
    r, allowed = [], []
    c3 = a[3][:-1] + a[3][1:]
    for k in range(len(floors)):
        g, g1 = d[k], d[k + 1]
        r.append(np.abs(np.diff(g) - h * (g1[:-1] + g1[1:]) / 2))
        if k == 0:
            allowed.append(h**2 * (a[2][:-1] + a[2][1:]) + h**3 * c3 / 6 + floors[k])
        else:  # the slope's and the second derivative's: a step times the third derivative
            allowed.append(h * c3 + floors[k])
    return np.array(r), np.array(allowed)


def jumps(
    law,
    start: float,
    stop: float,
    *,
    periodic: bool = False,
    n: int = 2048,
    zooms: int = 3,
    rtol: float = 1e-6,
    limit: int | None = None,
    order: int = 1,
) -> list[Jump]:
    """The jumps in value and slope (and, ``order`` 2, second derivative) of ``law`` on
    ``[start, stop]`` (see the module).

    Args:
        law: a scalar function of one variable, JAX-traceable (a :class:`~mixdyn.Law`).
        start, stop: the interval, in the law's variable.
        periodic: the law is read ``start + (x - start) mod (stop - start)`` (a cam's turn):
            the step that ends at ``stop`` compares the law before ``stop`` with the law at
            ``start`` (the wrap-around).
        n: steps of the grid, and of each closer look.
        zooms: closer looks at a step that seems to jump.
        rtol: jumps smaller than this times the law's scale are left.
        limit: stop after this many jumps (default: find them all).
        order: the highest derivative whose jumps are found: 1 (the slope, default) or 2
            (the second derivative).

    Returns:
        The jumps found, by place; empty for a law that is continuous with its derivatives
        up to ``order`` (or when the law cannot be sampled, or its numbers are being traced).
    """
    if order not in (1, 2):
        raise ValueError(f"order must be 1 or 2, got {order!r}")
    if (_smooth_to(law, order) and not periodic) or _traced(law) or not stop > start:
        return []
    if isinstance(law, PiecewisePolynomial):
        return _piecewise(law, start, stop, periodic, rtol, n, order)[:limit]
    key = _key(law, start, stop, periodic, n, zooms, rtol, limit, order)
    if key is not None and key in _FOUND:
        return list(_FOUND[key])
    found = _jumps(law, start, stop, periodic, n, zooms, rtol, limit, order)
    if found is None:  # a law that cannot be sampled (here) fails, named, when it is run
        return []
    if key is not None:
        if len(_FOUND) >= 256:
            _FOUND.pop(next(iter(_FOUND)))
        _FOUND[key] = tuple(found)
    return found


#: The jumps found, by law and interval (a sweep's members share their laws).
_FOUND: dict = {}


def _smooth_to(law, order: int) -> bool:
    """Whether ``law`` is continuous with its derivatives up to ``order`` by its form
    (:meth:`~mixdyn.model.Law.smooth_to`; a callable that is no Law: not known)."""
    # Read from the class: equinox makes a method read from a module a module of its own, at
    # every read (~20 us; a sweep checks every member's laws).
    smooth_to = getattr(type(law), "smooth_to", None)
    return bool(smooth_to(law, order)) if callable(smooth_to) else False


def _piecewise(law, start, stop, periodic, rtol, n, order=1) -> list[Jump]:
    """The jumps of a piecewise polynomial, from its pieces: at each break inside the span
    its pieces' values and slopes (and, ``order`` 2, second derivatives) meet (and,
    ``periodic``, the law's at ``stop`` and at ``start``), within what :func:`jumps` sees (a
    jump of a derivative less than the next derivative either side times a step of ``n``
    over the span is not seen)."""
    x = np.asarray(law.breaks, dtype=float)
    c = np.asarray(law.coeffs, dtype=float)
    m = c.shape[1]  # pieces
    derivatives = [_derivative(c, k) for k in range(order + 2)]

    def at(i, u, k):  # the k-th derivative of pieces i (n,) at u (n,)
        return _horner(derivatives[k], x, i, u)

    def piece(u):
        return np.clip(np.searchsorted(x, u, side="right") - 1, 0, m - 1)

    inner = [i for i in range(1, m) if start < x[i] < stop]
    b = x[inner]  # the breaks inside the span, and the pieces either side
    left, right, b_right = np.array(inner, dtype=int) - 1, np.array(inner, dtype=int), b
    if periodic:
        b = np.append(b, stop)
        left = np.append(left, piece(np.array([stop])))
        right = np.append(right, piece(np.array([start])))
        b_right = np.append(b_right, start)
    ends = np.array([start, stop, *b])
    values = at(piece(ends), ends, 0)
    slopes = at(piece(ends), ends, 1)
    scale0 = float(np.ptp(values))
    scale1 = float(np.max(np.abs(slopes))) + scale0 / (stop - start)
    floors = [rtol * scale0, rtol * scale1]
    if order == 2:
        knots = np.array([*ends, *x[:m], x[m - 1]])  # every piece at its start, the last at its end
        curvatures = at(piece(knots), knots, 2)
        floors.append(rtol * (float(np.max(np.abs(curvatures))) + scale1 / (stop - start)))
    h = (stop - start) / n
    jumped = []  # per derivative: (sizes, seen) at every break
    for k in range(order + 1):
        size = at(right, b_right, k) - at(left, b, k)
        bends = np.abs(at(left, b, k + 1)) + np.abs(at(right, b_right, k + 1))
        seen = (np.abs(size) > floors[k] + (k > 0) * h * bends) | ~np.isfinite(size)
        jumped.append((size, seen))
    found = []
    for p in range(len(b)):
        for k, (size, seen) in enumerate(jumped):
            if seen[p]:
                found.append(Jump(k, float(b[p]), float(size[p]), 0.0))
                break
    return found


def _derivative(c: np.ndarray, k: int) -> np.ndarray:
    """The coefficients ``(degree + 1 - k, pieces)`` of the pieces' ``k``-th derivatives,
    from their coefficients ``c`` ``(degree + 1, pieces)``, highest power first."""
    degree = c.shape[0] - 1
    if k > degree:
        return np.zeros((1, c.shape[1]))
    powers = np.arange(degree, -1, -1, dtype=float)
    for j in range(k):
        c = c * (powers - j)[:, None]
    return c[: degree + 1 - k]


def _horner(d: np.ndarray, x: np.ndarray, i: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Pieces ``i`` (n,) of coefficients ``d`` ``(rows, pieces)`` starting at breaks ``x``,
    evaluated at ``u`` (n,)."""
    du = np.asarray(u, dtype=float) - x[i]
    y = np.zeros_like(du)
    for row in d:
        y = y * du + row[i]
    return y


def _key(law, *args):
    """A hashable key of a law's structure and numbers, or None."""
    leaves, treedef = jax.tree_util.tree_flatten(law)
    try:
        key = (treedef, *(np.asarray(x).tobytes() for x in leaves), *args)
        hash(key)
    except TypeError:
        return None
    return key


def _jumps(law, start, stop, periodic, n, zooms, rtol, limit, order=1) -> list[Jump] | None:
    """:func:`jumps` of a law (None: it cannot be sampled, e.g. while a program is traced)."""
    period = stop - start
    f = _Turn(law, start, period) if periodic else law
    x = np.linspace(start, stop, n + 1)
    try:
        d = _samples(f, x)
    except Exception:
        return None
    bad = ~np.all(np.isfinite(d[:3]), axis=0)
    if bad.any():
        i = int(np.argmax(bad))
        return [Jump(0, float(x[i]), math.nan, 0.0, finite=False)]
    scale0 = float(np.ptp(d[0]))
    scale1 = float(np.max(np.abs(d[1]))) + scale0 / period
    floors = [rtol * scale0 + 1e-300, rtol * scale1 + 1e-300]
    if order == 2:
        floors.append(rtol * (float(np.max(np.abs(d[2]))) + scale1 / period) + 1e-300)
    r, allowed = _residuals(x, d, floors)
    found = []
    for i in np.flatnonzero(np.any(r > allowed, axis=0)):
        jump = _closer(f, x[i], x[i + 1], n, zooms, floors)
        if jump is not None:
            found.append(jump)
            if limit is not None and len(_merged(found, 2 * period / n)) >= limit:
                break
    return _merged(found, 2 * period / n)


def _closer(f, a: float, b: float, n: int, zooms: int, floors) -> Jump | None:
    """The jump within ``[a, b]``, looked at ``zooms`` times closer (None: none there)."""
    for _ in range(zooms):
        x = np.linspace(a, b, n + 1)
        d = _samples(f, x)
        if not np.all(np.isfinite(d[:3])):
            i = int(np.argmax(~np.all(np.isfinite(d[:3]), axis=0)))
            return Jump(0, float(x[i]), math.nan, float(b - a), finite=False)
        r, allowed = _residuals(x, d, floors)
        h = x[1] - x[0]
        up = [*(h * r[1:]), 0.0]  # a jump one order up explains this much of a residual
        for order in range(len(floors)):
            seen = r[order] > allowed[order] + up[order]
            if seen.any():
                i = int(np.argmax(r[order] * seen))
                break
        else:
            return None
        a, b = x[i], x[i + 1]
    size = float(d[order][i + 1] - d[order][i])
    return Jump(order, float((a + b) / 2), size, float(b - a))


def _merged(found: list[Jump], within: float) -> list[Jump]:
    """One jump per place (neighbouring steps may both see one at their common end)."""
    out: list[Jump] = []
    for j in sorted(found, key=lambda j: j.at):
        if out and abs(j.at - out[-1].at) <= within:
            if j.order < out[-1].order:
                out[-1] = j
            continue
        out.append(j)
    return out


def check(
    law,
    start: float,
    stop: float,
    *,
    element: str,
    moved: str,
    variable: str = "t",
    periodic: bool = False,
    field: str = "law",
    order: int = 1,
) -> None:
    """Refuse a law that jumps in value or slope (and, ``order`` 2, in its second
    derivative) on ``[start, stop]`` (see :func:`jumps`): a
    :class:`~mixdyn.errors.ModelError` of ``element`` at ``field`` naming the law, the place
    (``variable = ...``; an angle [rad] also in degrees) and the jump, and what it does to
    what the law ``moved`` (``"the follower"``); a jump of the second derivative also names
    the element's ``continuity: C1``, which accepts it.

    Raises:
        ModelError: the first jump found.
    """
    found = jumps(law, start, stop, periodic=periodic, limit=1, order=order)
    if not found:
        return
    j = found[0]
    place = f"{variable} = {j.at:.6g}"
    if variable != "t":
        place += f" rad ({math.degrees(j.at):.6g} deg)"
    if periodic and abs(j.at - stop) <= 2 * (stop - start) / 2048:
        place += f", where the turn wraps around to {variable} = {start:g}"
    if not j.finite:
        problem = (
            f"the law {_shown(law, variable)} or its slope or curvature is not finite at {place}"
        )
    else:
        problem = (
            f"the law {_shown(law, variable)} jumps by {j.size:+.6g} (model units) in its "
            f"{_WHAT[j.order]} at {place}: {moved} {_EFFECT[j.order]}"
        )
    what = "its slope" if order == 1 else "its slope and second derivative"
    ends = "value and slope" if order == 1 else "value, slope and second derivative"
    over = (
        f"over the turn, {variable} = {start:g} to {stop:.6g} (at the end its {ends} at the start)"
        if periodic
        else f"over the run, {variable} = {start:g} to {stop:g}"
    )
    if j.finite and j.order == 2:
        fix = (
            f"give a law continuous with {what} {over} (cycloidal, harmonic, 3-4-5 polynomial "
            "segments), or accept finite jumps of the acceleration (constant-acceleration "
            f"segments, a trapezoidal speed) with 'continuity: C1' on {element} "
            "(continuity='C1' in Python)"
        )
    else:
        fix = f"give a law continuous with {what} {over}"
        if order == 1:
            fix += "; its second derivative may jump"
    raise ModelError(f"{problem}; {fix}", element, field=field)


def _shown(law, variable: str) -> str:
    """The law in words: an expression's text (its variable named ``variable``), else its
    kind."""
    source = getattr(law, "source", None)
    if isinstance(source, str):
        return repr(re.sub(r"\bt\b", variable, source) if variable != "t" else source)
    return f"({type(law).__name__})"


__all__ = ["CONTINUITY", "CONTINUITY_DOC", "Jump", "check", "check_continuity", "jumps"]
