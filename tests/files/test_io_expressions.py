"""Safe expressions: values and exact derivatives, and every kind of refused input with the
column of the fault."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from mixdyn.io.expressions import (
    ExpressionError,
    ExpressionFunction,
    ExpressionLaw,
    constant_value,
    parse,
)


def test_value_and_exact_derivatives():
    law = ExpressionLaw("10*sin(pi*t/2)")
    for t in (0.0, 0.3, 1.0, 1.7):
        f, fd, fdd = law.derivatives(t)
        w = math.pi / 2
        assert float(f) == pytest.approx(10 * math.sin(w * t), abs=1e-14)
        assert float(fd) == pytest.approx(10 * w * math.cos(w * t), abs=1e-13)
        assert float(fdd) == pytest.approx(-10 * w**2 * math.sin(w * t), abs=1e-12)


def test_parameters_units_scale_and_vectorised_time():
    law = ExpressionLaw("F0*t**2 + 1", {"F0": 3.0, "unused": 9.0}, unit="N", scale=1000.0)
    assert law.names == ("F0",)  # only the parameters used are kept
    t = np.linspace(0, 2, 5)
    np.testing.assert_allclose(np.asarray(law(t)), 1000.0 * (3.0 * t**2 + 1))
    assert law.parameters == {"F0": 3.0}


def test_functions_and_comparisons():
    cases = {
        "where(t < 1, 2, 3)": lambda t: 2.0 if t < 1 else 3.0,
        "step(t, 0, 0, 1, 5)": lambda t: 5 * min(max(t, 0), 1) ** 2 * (3 - 2 * min(max(t, 0), 1)),
        "max(t, 0.5, 0.2)": lambda t: max(t, 0.5, 0.2),
        "atan2(1, t) + hypot(3, 4) + abs(-t) + t % 0.4": lambda t: (
            math.atan2(1, t) + 5 + t + math.fmod(t, 0.4)
        ),
        "(t >= 0.5) * 2 + (t != 0.3)": lambda t: 2.0 * (t >= 0.5) + (t != 0.3),
    }
    for src, fn in cases.items():
        law = ExpressionLaw(src)
        for t in (0.3, 0.75, 1.5):
            assert float(law(t)) == pytest.approx(fn(t), abs=1e-12), src


def test_step5_is_twice_differentiable_at_its_ends():
    law = ExpressionLaw("step5(t, 0, 0, 1, 1)")
    _, fd, fdd = law.derivatives(1.0)
    assert abs(float(fd)) < 1e-12 and abs(float(fdd)) < 1e-12


def test_equal_expressions_share_compiled_code():
    a, b = ExpressionLaw("2*sin(t)"), ExpressionLaw("2*sin(t)")
    assert jax.tree_util.tree_structure(a) == jax.tree_util.tree_structure(b)
    assert bool(eqx.tree_equal(a, b))
    traces = []

    @jax.jit
    def f(law, t):
        traces.append(1)
        return law(t)

    f(a, 1.0)
    f(b, 2.0)
    # a new parameter value is a leaf, not a new program
    f(ExpressionLaw("k*sin(t)", {"k": 1.0}), 1.0)
    f(ExpressionLaw("k*sin(t)", {"k": 5.0}), 1.0)
    assert len(traces) == 2


def test_state_expression_for_forces():
    fn = ExpressionFunction.of("-c*crank.omega + slider.x", ["crank", "slider"], {"c": 0.5})
    q = jnp.array([0.0, 0.0, 0.1, 2.0, 0.0, 0.0])
    qd = jnp.array([0.0, 0.0, 3.0, 0.0, 0.0, 0.0])
    assert float(fn(q, qd, 0.0)) == pytest.approx(-1.5 + 2.0)
    assert hash(fn) == hash(
        ExpressionFunction.of("-c*crank.omega + slider.x", ["crank", "slider"], {"c": 0.5})
    )
    sf = md.StateFunction(fn)
    assert float(sf(q, qd, 0.0)) == pytest.approx(0.5)


def test_constant_value():
    assert constant_value("pi/6") == pytest.approx(math.pi / 6)
    assert constant_value("2*L0 + 1", {"L0": 3.0}) == 7.0
    with pytest.raises(ExpressionError, match="'t' is not allowed"):
        constant_value("2*t")
    with pytest.raises(ExpressionError, match="not a finite number"):
        constant_value("10**10**10")


@pytest.mark.parametrize(
    ("source", "column", "message"),
    [
        ('__import__("os").system("ls")', 1, "only the listed functions may be called"),
        ("t.__class__", 2, "attribute access"),
        ("2 * t.__class__.__bases__", 6, "attribute access"),
        ("().__class__.__mro__", 1, "tuples not allowed"),
        ("open('x')", 1, "function 'open' is not allowed"),
        ("eval('1')", 1, "function 'eval' is not allowed"),
        ("sin(t)(1)", 1, "only the listed functions"),
        ("lambda: 1", 1, "lambda not allowed"),
        ("t[0]", 1, "subscripts"),
        ("'text'", 1, "is not a number"),
        ("x + 1", 1, "unknown name 'x'"),
        ("sin(t", 4, "syntax error"),
        ("sin(x=t)", 7, "keyword arguments"),
        ("sin(t, 2)", 1, "takes 1 argument"),
        ("t if t > 1 else 0", 1, "'if ... else' not allowed"),
        ("t and 1", 1, "'and'/'or' not allowed"),
        ("[t, 1]", 1, "lists not allowed"),
        ("(y := 2)", 2, "assignment"),
        ("t ^ 2", 1, "'^' is not a power"),
        ("1 < t < 2", 1, "chained comparisons"),
        ("True", 1, "is not a number"),
        ("1j", 1, "is not a number"),
        ("sin", 1, "must be called"),
        ("", None, "empty expression"),
        ("t" + "+t" * 600, None, "longer than"),
        ("sin(" * 70 + "t" + ")" * 70, None, "nested"),
    ],
)
def test_refused_with_position(source, column, message):
    with pytest.raises(ExpressionError) as info:
        parse(source)
    e = info.value
    assert message in str(e)
    if column is not None:
        assert e.column == column, str(e)
        assert f"column {column}" in str(e)
    assert "\n" not in str(e)


def test_state_references_only_where_allowed():
    with pytest.raises(ExpressionError, match="attribute access"):
        parse("crank.phi")  # no bodies: a law of time
    p = parse("crank.phi", bodies={"crank": 0})
    assert p.uses_state
    with pytest.raises(ExpressionError, match="has no state 'mass'"):
        parse("crank.mass", bodies={"crank": 0})
    with pytest.raises(ExpressionError, match="needs a state"):
        parse("crank + 1", bodies={"crank": 0})
