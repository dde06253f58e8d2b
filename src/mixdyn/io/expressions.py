"""Safe expressions for laws of time and state-dependent forces.

An expression is a formula in Python syntax, e.g. ``"10*sin(pi*t/2)"``. It may use

* numbers, the constants ``pi`` and ``e``, and the time ``t`` [model time unit];
* the parameters declared in the model file (by name);
* ``+ - * / % **``, parentheses, comparisons (``<``, ``<=``, ``>``, ``>=``, ``==``, ``!=``,
  worth 1 or 0);
* the functions in :data:`FUNCTIONS` (``sin``, ``where``, ``step``...);
* for force magnitudes only, the state of a body: ``crank.x``, ``crank.y``, ``crank.phi``,
  ``crank.vx``, ``crank.vy``, ``crank.omega``.

Nothing else: no attribute access, no subscripts, no calls of other names, no strings, no
lambdas. The text is parsed with :func:`ast.parse` (which never executes anything) and every
node is checked against that list; a fault is reported with its column. The accepted tree is
compiled to nested tuples and evaluated with ``jax.numpy``, so automatic differentiation gives
the derivatives of a law exactly.
"""

from __future__ import annotations

import ast
import dataclasses
import functools
import math
from collections.abc import Mapping

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._arrays import as_f64
from ..errors import ModelError
from ..model import Law

#: Longest expression accepted [characters].
MAX_LENGTH = 1000
#: Deepest nesting of operations accepted.
MAX_DEPTH = 60

CONSTANTS: dict[str, float] = {"pi": math.pi, "e": math.e}

#: State quantities of a body usable in force expressions: (array, index in [x, y, phi]).
STATE_ATTRIBUTES: dict[str, tuple[str, int]] = {
    "x": ("q", 0),
    "y": ("q", 1),
    "phi": ("q", 2),
    "vx": ("qd", 0),
    "vy": ("qd", 1),
    "omega": ("qd", 2),
}


def _step(xp, x, x0, h0, x1, h1):
    """ADAMS STEP: cubic blend from h0 at x0 to h1 at x1 (C1)."""
    s = xp.clip((x - x0) / (x1 - x0), 0.0, 1.0)
    return h0 + (h1 - h0) * s * s * (3.0 - 2.0 * s)


def _step5(xp, x, x0, h0, x1, h1):
    """Quintic blend from h0 at x0 to h1 at x1 (C2)."""
    s = xp.clip((x - x0) / (x1 - x0), 0.0, 1.0)
    return h0 + (h1 - h0) * s**3 * (10.0 - 15.0 * s + 6.0 * s * s)


def _reduce(op):
    return lambda xp, *a: functools.reduce(getattr(xp, op), a)


#: The functions an expression may call: name -> (implementation(xp, *args), min args, max
#: args, description).
FUNCTIONS: dict[str, tuple] = {
    "sin": (lambda xp, x: xp.sin(x), 1, 1, "sine"),
    "cos": (lambda xp, x: xp.cos(x), 1, 1, "cosine"),
    "tan": (lambda xp, x: xp.tan(x), 1, 1, "tangent"),
    "asin": (lambda xp, x: xp.arcsin(x), 1, 1, "inverse sine"),
    "acos": (lambda xp, x: xp.arccos(x), 1, 1, "inverse cosine"),
    "atan": (lambda xp, x: xp.arctan(x), 1, 1, "inverse tangent"),
    "atan2": (lambda xp, y, x: xp.arctan2(y, x), 2, 2, "four-quadrant inverse tangent (y, x)"),
    "sinh": (lambda xp, x: xp.sinh(x), 1, 1, "hyperbolic sine"),
    "cosh": (lambda xp, x: xp.cosh(x), 1, 1, "hyperbolic cosine"),
    "tanh": (lambda xp, x: xp.tanh(x), 1, 1, "hyperbolic tangent"),
    "exp": (lambda xp, x: xp.exp(x), 1, 1, "exponential"),
    "log": (lambda xp, x: xp.log(x), 1, 1, "natural logarithm"),
    "log10": (lambda xp, x: xp.log10(x), 1, 1, "decimal logarithm"),
    "sqrt": (lambda xp, x: xp.sqrt(x), 1, 1, "square root"),
    "abs": (lambda xp, x: xp.abs(x), 1, 1, "absolute value"),
    "sign": (lambda xp, x: xp.sign(x), 1, 1, "sign (-1, 0, 1)"),
    "floor": (lambda xp, x: xp.floor(x), 1, 1, "round down"),
    "ceil": (lambda xp, x: xp.ceil(x), 1, 1, "round up"),
    "hypot": (lambda xp, x, y: xp.hypot(x, y), 2, 2, "sqrt(x**2 + y**2)"),
    "min": (_reduce("minimum"), 2, 8, "smallest argument"),
    "max": (_reduce("maximum"), 2, 8, "largest argument"),
    "clip": (lambda xp, x, lo, hi: xp.clip(x, lo, hi), 3, 3, "x limited to [lo, hi]"),
    "where": (
        lambda xp, c, a, b: xp.where(c != 0, a, b),
        3,
        3,
        "where(condition, a, b): a where the condition holds, else b",
    ),
    "step": (_step, 5, 5, "step(x, x0, h0, x1, h1): cubic blend from h0 to h1 (ADAMS STEP)"),
    "step5": (_step5, 5, 5, "step5(x, x0, h0, x1, h1): quintic blend from h0 to h1"),
}

_BINOPS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**", ast.Mod: "%"}
_UNARY = {ast.UAdd: "+", ast.USub: "-"}
_COMPARE = {
    ast.Lt: "<",
    ast.LtE: "<=",
    ast.Gt: ">",
    ast.GtE: ">=",
    ast.Eq: "==",
    ast.NotEq: "!=",
}


class ExpressionError(ModelError):
    """An expression is not acceptable.

    Attributes:
        source: the expression text.
        column: 1-based column of the fault, or None.
        problem: what is wrong.
        hint: what to do.
    """

    def __init__(self, source: str, problem: str, column: int | None = None, hint: str = ""):
        self.source = source
        self.column = column
        self.problem = problem
        self.hint = hint
        where = f"column {column} of " if column else ""
        shown = source if len(source) <= 60 else source[:57] + "..."
        #: The message without the hint.
        self.message = f"{where}expression {shown!r}: {problem}"
        super().__init__(self.message + (f"; {hint}" if hint else ""))


@dataclasses.dataclass(frozen=True)
class Parsed:
    """A checked expression.

    Attributes:
        source: the text.
        tree: the compiled tree (nested tuples, hashable).
        parameters: names of the parameters it uses, in order of first use (the tree refers
            to them by index).
        uses_time: whether it uses ``t``.
        uses_state: whether it uses a body's state (a force magnitude).
    """

    source: str
    tree: tuple
    parameters: tuple[str, ...]
    uses_time: bool
    uses_state: bool


def _allowed_names(parameters, bodies, time) -> str:
    names = (["t"] if time else []) + list(CONSTANTS) + sorted(parameters)
    text = ", ".join(names)
    if bodies:
        text += ", body states like " + f"{next(iter(bodies))}.phi"
    return text


def parse(
    source: str,
    parameters=(),
    *,
    time: bool = True,
    bodies: dict[str, int] | None = None,
) -> Parsed:
    """Check and compile an expression.

    Args:
        source: the text, e.g. ``"10*sin(pi*t/2)"``.
        parameters: names of the declared parameters.
        time: whether ``t`` may be used.
        bodies: body name -> index, to allow state references (``crank.omega``); None to
            refuse them.

    Raises:
        ExpressionError: with the column of the first fault.
    """
    key = _cache_key(source, parameters, time) if bodies is None else None
    if key is None:
        return _parse(source, parameters, time=time, bodies=bodies)
    result = _parse_cached(key)
    if isinstance(result, Parsed):
        return result
    raise ExpressionError(*result) from None


#: Distinct (expression, parameter values, time allowed) parses remembered, refusals included.
CACHE_SIZE = 4096


def _cache_key(source, parameters, time) -> tuple | None:
    """A key that holds everything a parse without body states depends on (the parameters'
    names, and their values: a constant part that is not finite is refused), or None when
    the arguments are not plain (then the parse is not cached)."""
    if type(source) is not str or type(time) is not bool:
        return None
    if isinstance(parameters, Mapping):
        items = []
        for k, v in parameters.items():
            if type(k) is not str or type(v) is not float:
                return None
            items.append((k, v, math.copysign(1.0, v)))  # -0.0 and 0.0 kept apart
        return (source, time, True, tuple(items))
    if isinstance(parameters, tuple | list | set | frozenset) and all(
        type(k) is str for k in parameters
    ):
        return (source, time, False, frozenset(parameters))
    return None


@functools.lru_cache(maxsize=CACHE_SIZE)
def _parse_cached(key) -> Parsed | tuple:
    """The parse of a :func:`_cache_key` key, or the arguments of its ExpressionError."""
    source, time, mapping, params = key
    parameters = {k: v for k, v, _ in params} if mapping else params
    try:
        return _parse(source, parameters, time=time)
    except ExpressionError as e:
        return (e.source, e.problem, e.column, e.hint)


def _parse(
    source: str,
    parameters=(),
    *,
    time: bool = True,
    bodies: dict[str, int] | None = None,
) -> Parsed:
    """:func:`parse`, not cached."""
    if not isinstance(source, str):
        raise ExpressionError(str(source), "an expression must be a string")
    if len(source) > MAX_LENGTH:
        raise ExpressionError(
            source, f"longer than {MAX_LENGTH} characters", None, "split it using parameters"
        )
    if not source.strip():
        raise ExpressionError(source, "empty expression", None, "write a formula such as '2*t'")
    text = source.strip()
    # A leading space or newline would shift columns; ast counts from the stripped text.
    shift = len(source) - len(source.lstrip())
    try:
        node = ast.parse(text, mode="eval")
    except SyntaxError as e:
        col = (e.offset or 1) + shift
        raise ExpressionError(
            source,
            f"syntax error ({e.msg})",
            col,
            "write a formula in Python syntax, e.g. '10*sin(pi*t/2)'",
        ) from None
    except (RecursionError, MemoryError, ValueError):
        raise ExpressionError(source, "cannot be parsed (too deeply nested)", None, "") from None
    values = dict(parameters) if isinstance(parameters, Mapping) else None
    c = _Compiler(source, shift, frozenset(parameters), time, bodies, values)
    try:
        tree = c.compile(node.body, 0)
    except RecursionError:
        raise ExpressionError(source, "nested too deeply", None, "simplify it") from None
    return Parsed(source, tree, tuple(c.used), c.uses_time, c.uses_state)


class _Compiler:
    def __init__(self, source, shift, parameters, time, bodies, values=None):
        self.source = source
        self.values = values
        self._known: dict[tuple, float | None] = {}
        self.shift = shift
        self.parameters = parameters
        self.time = time
        self.bodies = bodies
        self.used: list[str] = []
        self.uses_time = False
        self.uses_state = False

    def fail(self, node, problem, hint=""):
        col = getattr(node, "col_offset", None)
        raise ExpressionError(
            self.source, problem, None if col is None else col + 1 + self.shift, hint
        )

    def compile(self, node, depth):
        tree = self._compile(node, depth)
        if tree[0] in ("b", "u", "k", "f"):
            self._check_constant(node, tree)
        return tree

    def constant(self, tree) -> float | None:
        """The value of a subtree that depends on neither ``t`` nor a state (else None)."""
        if tree in self._known:
            return self._known[tree]
        tag = tree[0]
        if tag in ("t", "s") or (tag == "p" and self.values is None):
            value = None
        elif tag == "c":
            value = tree[1]
        elif tag == "p":
            value = float(self.values[self.used[tree[1]]])
        else:
            args = tree[2:] if tag in ("u", "b", "k") else tree[2]
            known = [self.constant(a) for a in args]
            value = None if any(v is None for v in known) else _numeric(tree, self.values_of())
        self._known[tree] = value
        return value

    def values_of(self) -> list[float]:
        return [float(self.values[n]) for n in self.used] if self.values is not None else []

    def _check_constant(self, node, tree):
        """Refuse a division by a constant zero and a constant part that is not finite."""
        if tree[0] == "b" and tree[1] in ("/", "%") and self.constant(tree[3]) == 0.0:
            what = "division" if tree[1] == "/" else "remainder"
            self.fail(node, f"{what} by zero", "the divisor is always 0")
        value = self.constant(tree)
        if value is not None and not math.isfinite(value):
            part = _segment(self.source, node)
            self.fail(
                node,
                f"{part!r} is not a finite number ({value!r})",
                "check the arguments (a logarithm or root of a negative number, an overflow)",
            )

    def _compile(self, node, depth):
        if depth > MAX_DEPTH:
            self.fail(node, f"nested more than {MAX_DEPTH} levels deep", "simplify it")
        d = depth + 1
        if isinstance(node, ast.Constant):
            v = node.value
            if isinstance(v, bool) or not isinstance(v, int | float):
                self.fail(node, f"{v!r} is not a number", "only numbers are allowed as literals")
            try:
                x = float(v)
            except OverflowError:
                self.fail(node, "number too large")
            if not math.isfinite(x):
                self.fail(node, "number too large")
            return ("c", x)
        if isinstance(node, ast.Name):
            return self.name(node)
        if isinstance(node, ast.BinOp):
            op = _BINOPS.get(type(node.op))
            if isinstance(node.op, ast.BitXor):
                self.fail(node, "'^' is not a power here", "write powers with **, e.g. L**2")
            if op is None:
                self.fail(node, f"operator {type(node.op).__name__} is not allowed", _OPS_HINT)
            return ("b", op, self.compile(node.left, d), self.compile(node.right, d))
        if isinstance(node, ast.UnaryOp):
            op = _UNARY.get(type(node.op))
            if op is None:
                self.fail(node, f"operator {type(node.op).__name__} is not allowed", _OPS_HINT)
            return ("u", op, self.compile(node.operand, d))
        if isinstance(node, ast.Compare):
            if len(node.ops) != 1:
                self.fail(node, "chained comparisons are not allowed", "compare two values")
            op = _COMPARE.get(type(node.ops[0]))
            if op is None:
                self.fail(node, f"comparison {type(node.ops[0]).__name__} is not allowed")
            return ("k", op, self.compile(node.left, d), self.compile(node.comparators[0], d))
        if isinstance(node, ast.Call):
            return self.call(node, d)
        if isinstance(node, ast.Attribute):
            return self.attribute(node)
        what = {
            ast.Subscript: "subscripts ([...])",
            ast.Lambda: "lambda",
            ast.IfExp: "'if ... else'",
            ast.BoolOp: "'and'/'or'",
            ast.List: "lists",
            ast.Tuple: "tuples",
            ast.Dict: "dicts",
            ast.Set: "sets",
            ast.JoinedStr: "strings",
            ast.NamedExpr: "assignment (:=)",
            ast.Starred: "'*' unpacking",
        }.get(type(node), type(node).__name__)
        self.fail(node, f"{what} not allowed", "use numbers, t, parameters and functions")

    def name(self, node):
        n = node.id
        if n == "t":
            if not self.time:
                self.fail(node, "'t' is not allowed here", "a constant cannot depend on time")
            self.uses_time = True
            return ("t",)
        if n in self.parameters:
            if n not in self.used:
                self.used.append(n)
            return ("p", self.used.index(n))
        if n in CONSTANTS:
            return ("c", CONSTANTS[n])
        if n in FUNCTIONS:
            self.fail(node, f"function {n!r} must be called", f"write {n}(...)")
        if self.bodies and n in self.bodies:
            self.fail(node, f"body {n!r} needs a state", f"write e.g. {n}.phi or {n}.omega")
        self.fail(
            node,
            f"unknown name {n!r}",
            "allowed names: " + _allowed_names(self.parameters, self.bodies, self.time),
        )

    def attribute(self, node):
        base = node.value
        if (
            self.bodies is not None
            and isinstance(base, ast.Name)
            and base.id in self.bodies
            and node.attr in STATE_ATTRIBUTES
        ):
            arr, k = STATE_ATTRIBUTES[node.attr]
            self.uses_state = True
            return ("s", arr, 3 * self.bodies[base.id] + k)
        if self.bodies is not None and isinstance(base, ast.Name) and base.id in self.bodies:
            self.fail(
                node,
                f"body {base.id!r} has no state {node.attr!r}",
                f"use one of {', '.join(STATE_ATTRIBUTES)}",
            )
        if not isinstance(base, ast.Name):
            self.compile(base, 0)  # report the leftmost fault first
        dot = ast.Name(id="", col_offset=getattr(base, "end_col_offset", node.col_offset))
        self.fail(
            dot,
            f"attribute access ('.{node.attr}') is not allowed",
            "expressions may use numbers, t, parameters and the listed functions"
            + ("" if self.bodies is None else ", and body states like crank.phi"),
        )

    def call(self, node, d):
        f = node.func
        if not isinstance(f, ast.Name):
            self.fail(node, "only the listed functions may be called", _FUNCS_HINT)
        if f.id not in FUNCTIONS:
            self.fail(node, f"function {f.id!r} is not allowed", _FUNCS_HINT)
        if node.keywords:
            self.fail(node.keywords[0].value, "keyword arguments are not allowed")
        _, lo, hi, _desc = FUNCTIONS[f.id]
        n = len(node.args)
        if not lo <= n <= hi:
            want = str(lo) if lo == hi else f"{lo} to {hi}"
            self.fail(node, f"{f.id}() takes {want} argument(s), got {n}")
        return ("f", f.id, tuple(self.compile(a, d) for a in node.args))


def _numeric(tree, values) -> float:
    """Evaluate a constant tree with NumPy; any arithmetic fault gives NaN."""
    try:
        with np.errstate(all="ignore"):
            return float(np.asarray(evaluate(tree, 0.0, values, xp=np), dtype=float))
    except (ArithmeticError, ValueError, TypeError, RecursionError, MemoryError):
        return math.nan


def _segment(source: str, node) -> str:
    """The text of ``node`` in ``source`` (shortened), for messages."""
    text = ast.get_source_segment(source.strip(), node) or source
    return text if len(text) <= 40 else text[:37] + "..."


_OPS_HINT = "use + - * / % ** and comparisons"
_FUNCS_HINT = "allowed functions: " + ", ".join(FUNCTIONS)


def evaluate(tree: tuple, t, values, q=None, qd=None, xp=jnp):
    """Evaluate a compiled tree with ``xp`` (``jax.numpy`` or ``numpy``)."""
    tag = tree[0]
    if tag == "c":
        return tree[1]
    if tag == "t":
        return t
    if tag == "p":
        return values[tree[1]]
    if tag == "s":
        return (q if tree[1] == "q" else qd)[tree[2]]
    if tag == "u":
        x = evaluate(tree[2], t, values, q, qd, xp)
        return -x if tree[1] == "-" else x
    if tag == "b":
        a = evaluate(tree[2], t, values, q, qd, xp)
        b = evaluate(tree[3], t, values, q, qd, xp)
        op = tree[1]
        if op == "+":
            return a + b
        if op == "-":
            return a - b
        if op == "*":
            return a * b
        if op == "/":
            return xp.true_divide(a, b)
        if op == "%":
            return xp.mod(a, b)
        return xp.power(a, b)
    if tag == "k":
        a = evaluate(tree[2], t, values, q, qd, xp)
        b = evaluate(tree[3], t, values, q, qd, xp)
        op = tree[1]
        cond = {
            "<": xp.less,
            "<=": xp.less_equal,
            ">": xp.greater,
            ">=": xp.greater_equal,
            "==": xp.equal,
            "!=": xp.not_equal,
        }[op](a, b)
        return xp.where(cond, 1.0, 0.0)
    if tag == "f":
        fn = FUNCTIONS[tree[1]][0]
        return fn(xp, *(evaluate(a, t, values, q, qd, xp) for a in tree[2]))
    raise AssertionError(tag)


def constant_value(source: str, parameters: dict[str, float] | None = None) -> float:
    """The value of a constant expression (no ``t``), e.g. ``"pi/6"`` or ``"2*L0"``.

    Raises:
        ExpressionError: not a valid constant expression, or not a finite number.
    """
    parameters = dict(parameters or {})
    p = parse(source, parameters, time=False)
    x = _numeric(p.tree, [parameters[n] for n in p.parameters])
    if not math.isfinite(x):
        raise ExpressionError(source, f"the value is not a finite number ({x!r})")
    return x


class ExpressionLaw(Law):
    """A law of time written as an expression, e.g. ``ExpressionLaw("10*sin(pi*t/2)")``.

    The value is ``scale * expression(t)``; ``scale`` converts the expression's ``unit`` into
    the model's unit. Parameters are array leaves (changing a value does not recompile); the
    compiled tree is static.

    Args:
        source: the expression (see the module's documentation for what it may use).
        parameters: values of the parameters it may use, by name [model units].
        unit: the unit the expression's value is in, as written in the file (None: model units).
        scale: model units per ``unit``.
    """

    source: str = eqx.field(static=True)
    tree: tuple = eqx.field(static=True)
    names: tuple[str, ...] = eqx.field(static=True)
    unit: str | None = eqx.field(static=True)
    values: jax.Array
    scale: jax.Array

    def __init__(self, source: str, parameters=None, unit: str | None = None, scale=1.0):
        parameters = dict(parameters or {})
        p = parse(source, parameters, time=True)
        self.source = source
        self.tree = p.tree
        self.names = p.parameters
        self.unit = unit
        self.values = as_f64([float(parameters[n]) for n in p.parameters])
        self.scale = as_f64(float(scale))

    def __call__(self, t):
        t = jnp.asarray(t, dtype=jnp.float64)
        return self.scale * (evaluate(self.tree, t, self.values) + 0.0 * t)

    @property
    def parameters(self) -> dict[str, float]:
        """The parameters it uses with their values."""
        return {n: float(v) for n, v in zip(self.names, np.asarray(self.values), strict=True)}

    @property
    def smooth(self) -> bool:
        """Continuous with its slope for every ``t`` by its form (sums, products, quotients
        by constants, whole powers, ``sin cos sinh cosh tanh exp atan`` and ``step``,
        ``step5`` blends of such terms; no ``where``, ``abs``, ``floor``, comparisons...),
        so that :mod:`mixdyn.model._smoothness` need not sample it."""
        return _smooth(self.tree)

    def smooth_to(self, order: int) -> bool:
        """Continuous with its derivatives up to ``order`` by its form (:attr:`smooth`;
        for ``order`` 2 without ``step``, whose cubic blend's second derivative jumps at its
        ends)."""
        return _smooth(self.tree, order)


#: The functions that are smooth (every derivative continuous) wherever their arguments are.
_SMOOTH_FUNCTIONS = frozenset({"sin", "cos", "sinh", "cosh", "tanh", "exp", "atan"})


def _has_t(tree) -> bool:
    if tree[0] in ("t", "s"):
        return True
    return any(isinstance(x, tuple) and x and _has_t(x) for x in _children(tree))


def _children(tree) -> tuple:
    tag = tree[0]
    if tag == "u":
        return (tree[2],)
    if tag in ("b", "k"):
        return (tree[2], tree[3])
    if tag == "f":
        return tuple(tree[2])
    return ()


#: The order up to which each blend's derivatives are continuous (its value at both ends
#: constant): ``step`` cubic (C1), ``step5`` quintic (C2).
_BLENDS = {"step": 1, "step5": 2}


def _smooth(tree, order: int = 1) -> bool:
    """An expression tree continuous with its derivatives in ``t`` up to ``order`` for every
    ``t``."""
    tag = tree[0]
    if not _has_t(tree):
        return True
    if tag == "t":
        return True
    if tag == "u":
        return _smooth(tree[2], order)
    if tag == "b":
        op, a, b = tree[1], tree[2], tree[3]
        if op in ("+", "-", "*"):
            return _smooth(a, order) and _smooth(b, order)
        if op == "/":
            return _smooth(a, order) and not _has_t(b)
        if op == "**":
            whole = b[0] == "c" and float(b[1]) >= 0 and float(b[1]).is_integer()
            return (_smooth(a, order) and whole) or (not _has_t(a) and _smooth(b, order))
        return False
    if tag == "f":
        name, args = tree[1], tuple(tree[2])
        if name in _SMOOTH_FUNCTIONS:
            return all(_smooth(a, order) for a in args)
        if _BLENDS.get(name, 0) >= order:  # blends of x between constant ends
            return _smooth(args[0], order) and not any(_has_t(a) for a in args[1:])
    return False


@dataclasses.dataclass(frozen=True)
class ExpressionFunction:
    """A force magnitude ``fn(q, qd, t)`` written as an expression of time and body states.

    Wrap it in :class:`mixdyn.StateFunction`. It is hashable by value, so equal expressions
    share compiled code.

    Attributes:
        source: the expression, e.g. ``"-0.2*crank.omega"``.
        tree: its compiled tree.
        names: parameters used; ``values`` their values [model units].
        unit: the unit of the value as written (None: model units); ``scale`` model units per
            ``unit``.
        bodies: body names in model order (for writing the expression back).
    """

    source: str
    tree: tuple
    names: tuple[str, ...]
    values: tuple[float, ...]
    unit: str | None
    scale: float
    bodies: tuple[str, ...]

    @classmethod
    def of(cls, source, bodies, parameters=None, unit=None, scale=1.0) -> ExpressionFunction:
        parameters = dict(parameters or {})
        bodies = tuple(bodies)
        p = parse(source, parameters, time=True, bodies={b: i for i, b in enumerate(bodies)})
        return cls._of_parsed(p, bodies, parameters, unit, scale)

    @classmethod
    def _of_parsed(
        cls, parsed: Parsed, bodies, parameters=None, unit=None, scale=1.0
    ) -> ExpressionFunction:
        """:meth:`of` from the parse of its source with ``bodies={b: i for i, b in
        enumerate(bodies)}`` (a caller that has parsed it already parses it once)."""
        parameters = parameters or {}
        vals = tuple(float(parameters[n]) for n in parsed.parameters)
        return cls(
            parsed.source, parsed.tree, parsed.parameters, vals, unit, float(scale), tuple(bodies)
        )

    def __call__(self, q, qd, t):
        t = jnp.asarray(t, dtype=jnp.float64)
        v = evaluate(self.tree, t, jnp.asarray(self.values, dtype=jnp.float64), q, qd)
        return self.scale * (v + 0.0 * t)

    @property
    def parameters(self) -> dict[str, float]:
        return dict(zip(self.names, self.values, strict=True))
