"""`mixdyn check` in time and memory linear in the model's size (issue "Trustworthy results").

* The sparse mobility analysis (sparse Jacobian, rank-revealing QR only around the
  redundancies) gives the dense analysis' rank, redundant equations, redundant drivers and
  degrees of freedom, on mechanisms with and without redundant joints and drivers.
* A generated 2,000-body chain is checked without a dense Jacobian and with a bounded number
  of traced programs (counted, not timed).
"""

from __future__ import annotations

import importlib.util
import pathlib

import jax
import numpy as np
import pytest
from typer.testing import CliRunner

import mixdyn as md
from fixtures import ROOT, double_four_bar, four_bar, parallelogram_with_extra_link, pendulum_chain
from mixdyn.analysis import _structure
from mixdyn.equations import Constraints
from mixdyn.equations import _constraints as ec

jax.config.update("jax_enable_x64", True)


def _chain_yaml(n: int) -> str:
    spec = importlib.util.spec_from_file_location(
        "check_scaling", ROOT / "benchmarks" / "check_scaling.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.chain_yaml(n)


def _both(model, q, drivers=None, t=0.0):
    dense = _structure.analyse(model, q, t, drivers, method="dense")
    sparse = _structure.analyse(model, q, t, drivers, method="sparse")
    return dense, sparse


def _assembled(model, hold=()):
    return md.assemble(model, hold=hold).q


def _chain_with_parallelogram(n: int):
    """A pendulum chain of ``n`` links whose last link carries a parallelogram with an extra
    link (one redundant joint equation at the far end of a long chain)."""
    base = parallelogram_with_extra_link()
    chain = pendulum_chain(n)
    # the parallelogram's ground pivots on the chain's last link
    tip = chain.bodies[-1]
    bodies = [*chain.bodies]
    pts = dict(tip.points)
    pts.update({"O1": (0.0, 0.0), "O2": (0.5, 0.0), "O3": (0.2, 0.0)})
    bodies[-1] = md.Body(tip.name, 1.0, 0.1, q0=tuple(np.asarray(tip.q0)), points=pts)
    joints = [*chain.joints]
    for j in base.joints:
        pi = j.point_i.replace("ground.", f"{tip.name}.")
        joints.append(md.Revolute(j.name, pi, j.point_j))
    # the parallelogram's bodies placed in the tip's frame (a start close to closing)
    x, y, phi = np.asarray(tip.q0, dtype=float)
    c, s = np.cos(phi), np.sin(phi)
    moved = []
    for b in base.bodies:
        bx, by, bphi = np.asarray(b.q0, dtype=float)
        q0 = (x + c * bx - s * by, y + s * bx + c * by, phi + bphi)
        moved.append(md.Body(b.name, 1.0, 0.01, q0=q0, points=dict(b.points)))
    return md.Model(
        [*bodies, *moved],
        joints,
        ground=chain.ground,
        name="chain+parallelogram",
    )


@pytest.mark.parametrize(
    "build",
    [
        lambda: parallelogram_with_extra_link(),
        lambda: four_bar(),
        lambda: double_four_bar(2)[0],
        lambda: double_four_bar(5)[0],
    ],
    ids=["parallelogram", "four_bar", "double_four_bar_2", "double_four_bar_5"],
)
def test_sparse_analysis_equals_dense_on_fixtures(build):
    model = build()
    q = _assembled(model.replace(drivers=()))
    (rd, kd), (rs, ks) = _both(model, q)
    assert rs == rd
    assert ks == kd


def test_redundant_equation_found_by_the_sparse_analysis():
    model = parallelogram_with_extra_link()
    q = _assembled(model.replace(drivers=()))
    report, keep = _structure.analyse(model, q, method="sparse")
    assert (report.n_coordinates, report.rank, report.dof) == (12, 11, 1)
    assert len(report.redundant) == 1
    assert len(keep) == 12  # 11 joint rows and the driver


def test_redundant_drivers_sparse_equals_dense():
    """A second driver that repeats the first (the parallelogram's follower turns with its
    crank), and a driver on a coordinate the joints fix."""
    model = parallelogram_with_extra_link()
    q = _assembled(model.replace(drivers=()))
    motor = model.drivers[0]
    drivers = [
        motor,
        md.CoordinateDriver("follower_angle", "follower", "phi", law=md.Constant(float(q[5]))),
        md.CoordinateDriver("coupler_angle", "coupler", "phi", law=md.Constant(0.0)),
    ]
    model2 = model.replace(drivers=drivers)
    (rd, kd), (rs, ks) = _both(model2, q)
    assert rd.redundant_drivers == ("follower_angle", "coupler_angle")
    assert rs == rd
    assert ks == kd


def test_chain_sparse_equals_dense():
    model = pendulum_chain(60)
    q = _assembled(model)
    drivers = [
        md.CoordinateDriver("a0", "link0", "phi", law=md.Constant(float(q[2]))),
        md.CoordinateDriver("a1", "link1", "phi", law=md.Constant(float(q[5]))),
        # the same coordinate twice: redundant
        md.CoordinateDriver("a1_again", "link1", "phi", law=md.Constant(float(q[5]))),
    ]
    (rd, kd), (rs, ks) = _both(model.replace(drivers=drivers), q)
    assert rd.redundant_drivers == ("a1_again",)
    assert (rd.dof, rd.rank) == (60, 120)
    assert rs == rd
    assert ks == kd


@pytest.mark.slow  # a long scaling run (CI runs it)
def test_redundancy_at_the_end_of_a_long_chain_is_analysed_locally(monkeypatch):
    """One redundant equation at the end of a 400-link chain: the dense QR sees only the rows
    around it. Rank, degrees of freedom and the number of redundant equations are the dense
    analysis'; which equation of the loop is dropped may differ (the column-pivoted QR's
    choice among equally good rows depends on every row), but the rows kept are a maximal
    independent set."""
    model = _chain_with_parallelogram(400)
    q = _assembled(model)
    sizes = []
    dense_rows = _structure.independent_rows

    def counting(A, rtol=1e-9):
        sizes.append(np.shape(A))
        return dense_rows(A, rtol)

    monkeypatch.setattr(_structure, "independent_rows", counting)
    rs, ks = _structure.analyse(model, q, method="sparse")
    assert sizes and max(s[0] for s in sizes) < 100  # the neighbourhood, not 812 rows
    monkeypatch.setattr(_structure, "independent_rows", dense_rows)
    rd, _ = _structure.analyse(model, q, method="dense")
    assert rd.rank == model.n_joint_equations - 1
    assert (rs.rank, rs.dof, rs.n_equations) == (rd.rank, rd.dof, rd.n_equations)
    assert len(rs.redundant) == len(rd.redundant) == 1
    assert rs.redundant[0].split(".")[0] in ("O1", "O2", "O3", "P1", "P2", "P3")
    J = np.asarray(Constraints.of(model).phi_q(q, 0.0))
    assert dense_rows(J[list(ks)])[2] == len(ks) == rd.rank


def test_sparse_independent_rows_on_a_banded_matrix():
    rng = np.random.default_rng(3)
    A = np.zeros((40, 60))
    for i in range(40):  # a band
        A[i, 1 * i : 1 * i + 5] = rng.standard_normal(5)
    A[17] = A[15] - 2 * A[16]  # dependent on its neighbours
    A[30] = 0.0  # a zero row
    dense = _structure.independent_rows(A)
    sparse = _structure.independent_rows_sparse(A)
    assert dense[2] == sparse[2] == 38
    assert 30 in sparse[1] and set(sparse[1]) <= {15, 16, 17, 30}
    assert _structure.independent_rows(A[sparse[0]])[2] == 38  # a maximal independent set


def test_constraints_static_layout_shared_by_copies_and_structures():
    model = pendulum_chain(20)
    c = Constraints.of(model)
    st = c._static()
    assert c.with_linear_solver("sparse")._static() is st
    assert c.with_active(range(c.n_full - 1))._static() is st
    # another model of the same structure, other numbers: the same layout
    assert Constraints.of(pendulum_chain(20, link=2.0))._static() is st


def test_packed_matches_constraints():
    model = pendulum_chain(40)
    q = _assembled(model)
    c = Constraints.of(model, ()).with_linear_solver("sparse")
    p = c.packed()
    t = 0.0
    np.testing.assert_array_equal(np.asarray(p.full(q, t)), np.asarray(c.full(q, t)))
    np.testing.assert_array_equal(
        np.asarray(p.jacobian_values(q, t)), np.asarray(c.jacobian_values(q, t))
    )
    assert len(jax.tree.leaves(p)) < 10  # a few stacked arrays, not one per joint


def test_model_q0_and_masses_with_numpy():
    model = pendulum_chain(5)
    q0 = np.concatenate([np.asarray(b.q0) for b in model.bodies])
    np.testing.assert_array_equal(np.asarray(model.q0), q0)
    m = np.asarray(model.mass_diagonal)
    assert m.shape == (15,)
    np.testing.assert_array_equal(m[0::3], [float(b.mass) for b in model.bodies])
    np.testing.assert_array_equal(m[2::3], [float(b.inertia) for b in model.bodies])
    # inside a trace: JAX
    total = jax.jit(lambda mod: mod.mass_diagonal.sum() + mod.q0.sum())(model)
    assert np.isfinite(float(total))


@pytest.mark.slow  # a long scaling run (CI runs it)
def test_check_of_a_2000_body_chain_is_sparse_and_compiles_a_bounded_number_of_programs(
    tmp_path, monkeypatch
):
    """No dense Jacobian is formed, and the compiled programs do not grow with the chain:
    each per-element evaluation is traced a bounded number of times."""
    from mixdyn.cli import app

    path = tmp_path / "chain.yaml"
    path.write_text(_chain_yaml(2000))

    def no_dense(*args, **kwargs):
        raise AssertionError("a dense Jacobian was formed")

    monkeypatch.setattr(_structure, "_jac", no_dense)
    monkeypatch.setattr(Constraints, "phi_q", no_dense)
    traces = {"local": 0, "jacobian": 0, "elements": 0}
    local, jac, residual = ec._local_eval, ec._jacobian_eval, ec._residual

    def count_local(*args, **kwargs):
        traces["local"] += 1
        return local(*args, **kwargs)

    def count_jac(*args, **kwargs):
        traces["jacobian"] += 1
        return jac(*args, **kwargs)

    def count_residual(*args, **kwargs):
        traces["elements"] += 1  # once per vmapped evaluation, not per joint
        return residual(*args, **kwargs)

    monkeypatch.setattr(ec, "_local_eval", count_local)
    monkeypatch.setattr(ec, "_jacobian_eval", count_jac)
    monkeypatch.setattr(ec, "_residual", count_residual)
    jax.clear_caches()  # fresh compilations: the counts do not depend on earlier tests
    result = CliRunner().invoke(app, ["check", str(path)])
    assert result.exit_code == 0, result.output
    assert "degrees of freedom: 2000" in result.output
    assert "redundant joint equations: none" in result.output
    assert 1 <= traces["local"] <= 6
    assert 1 <= traces["jacobian"] <= 6
    assert traces["elements"] <= 20


def test_large_assembly_retries_a_failed_sparse_step_damped_not_dense(monkeypatch):
    """A sparse step refused (as redundant equations make ``J J^T`` singular) is taken again
    on the sparse path with a damping floor for a large model, not on the dense path."""
    from mixdyn.analysis import _assembly

    model = _chain_with_parallelogram(40)
    q = np.asarray(model.q0, dtype=float).copy()
    q[-12:] += 0.05 * np.random.default_rng(0).standard_normal(12)
    monkeypatch.setattr(_assembly, "SPARSE_STEP_MIN_RATIO", 2.0)  # every step refused
    monkeypatch.setattr(_assembly, "DENSE_FALLBACK_MAX_ENTRIES", 0)

    def no_dense(*args, **kwargs):
        raise AssertionError("dense step")

    monkeypatch.setattr(_assembly, "_gn_step", no_dense)
    asm = md.assemble(model, q, linear_solver="sparse")
    assert asm.residual <= 1e-12 * _assembly.length_scale(model)
    assert md.degrees_of_freedom(model, asm.q).rank == model.n_joint_equations - 1


def test_size_limit_is_an_input_error():
    _structure.require_checkable(_structure.MAX_BODIES)
    with pytest.raises(md.ModelError, match=f"at most {_structure.MAX_BODIES:,} bodies"):
        _structure.require_checkable(_structure.MAX_BODIES + 1, "big.yaml")


def test_cli_refuses_a_model_over_the_size_limit_before_building_it(monkeypatch):
    """``mixdyn check`` and ``mixdyn run`` refuse a model over the stated limit with one line
    and exit 2, before building it (the limit lowered to 1 body for the test)."""
    from mixdyn.cli import app

    monkeypatch.setattr(_structure, "MAX_BODIES", 1)
    example = ROOT / "examples" / "four_bar.yaml"
    for args in (["check", str(example)], ["run", str(example), "--out", "unused"]):
        res = CliRunner().invoke(app, args)
        assert res.exit_code == 2, res.output
        assert "at most 1 bodies" in res.stderr
        assert len(res.stderr.strip().splitlines()) == 1
        assert not pathlib.Path("unused").exists()
