"""Kinematic analysis against closed-form solutions: slider–crank, four-bar (Freudenstein),
a parallelogram with a redundant link; point trajectories; compile once per structure."""

import importlib

import numpy as np
import pytest

import mixdyn as md
from fixtures import four_bar, parallelogram_with_extra_link, slider_crank
from mixdyn.equations import Constraints

# ------------------------------------------------------------------------- slider-crank
R, L, OMEGA = 0.1, 0.3, 2.0


def slider_closed_form(r, l, omega, th):
    """Slider position, velocity and acceleration at crank angle ``th`` turning at constant
    ``omega``: ``x = r cos th + S``, ``S = sqrt(l^2 - g)``, ``g = r^2 sin^2 th``, differentiated
    by hand: ``S' = -g'/(2S)``, ``S'' = -g''/(2S) - g'^2/(4S^3)``."""
    g = r**2 * np.sin(th) ** 2
    g1 = r**2 * np.sin(2 * th)
    g2 = 2 * r**2 * np.cos(2 * th)
    S = np.sqrt(l**2 - g)
    S1 = -g1 / (2 * S)
    S2 = -g2 / (2 * S) - g1**2 / (4 * S**3)
    x = r * np.cos(th) + S
    v = (-r * np.sin(th) + S1) * omega
    a = (-r * np.cos(th) + S2) * omega**2
    return x, v, a


@pytest.fixture(scope="module")
def crank_run():
    t = np.linspace(0.0, np.pi / OMEGA, 64)  # one crank turn, 64 angles
    return md.kinematic(slider_crank(R, L, OMEGA), t)


def assert_close_rel(actual, expected, rel):
    """``|actual - expected| <= rel * max|expected|`` elementwise."""
    scale = np.max(np.abs(expected))
    np.testing.assert_allclose(actual, expected, rtol=0, atol=rel * scale)


def test_slider_crank_matches_closed_form(crank_run):
    res = crank_run
    th = OMEGA * res.t
    x, v, a = slider_closed_form(R, L, OMEGA, th)
    assert_close_rel(res["slider.x"], x, 1e-9)
    assert_close_rel(res["slider.vx"], v, 1e-9)
    assert_close_rel(res["slider.ax"], a, 1e-9)
    # The crank follows its driver exactly, the slider stays on its line, no rotation.
    assert_close_rel(res["crank.phi"], th, 1e-12)
    np.testing.assert_allclose(res["crank.omega"], OMEGA, rtol=1e-12)
    np.testing.assert_allclose(res["crank.alpha"], 0.0, atol=1e-9)
    np.testing.assert_allclose(res["slider.y"], 0.0, atol=1e-12)
    np.testing.assert_allclose(res["slider.phi"], 0.0, atol=1e-12)


def test_slider_crank_rod_matches_closed_form(crank_run):
    """The rod angle ``beta = asin(-r sin th / l)``: ``beta' = -r cos th w / S`` and
    ``beta'' = w^2 (r sin th / S + r cos th S' / S^2)`` (``S = l cos beta``)."""
    res = crank_run
    th = OMEGA * res.t
    S = np.sqrt(L**2 - (R * np.sin(th)) ** 2)
    S1 = -(R**2) * np.sin(2 * th) / (2 * S)
    beta = np.arcsin(-R * np.sin(th) / L)
    beta_d = -R * np.cos(th) * OMEGA / S
    beta_dd = OMEGA**2 * (R * np.sin(th) / S + R * np.cos(th) * S1 / S**2)
    assert_close_rel(res["rod.phi"], beta, 1e-9)
    assert_close_rel(res["rod.omega"], beta_d, 1e-9)
    assert_close_rel(res["rod.alpha"], beta_dd, 1e-9)
    # rod centre halfway between crank pin and slider
    assert_close_rel(res["rod.x"], 0.5 * (R * np.cos(th) + res["slider.x"]), 1e-12)
    assert_close_rel(res["rod.y"], 0.5 * R * np.sin(th), 1e-12)


def test_slider_crank_stats(crank_run):
    stats = crank_run.stats
    assert stats["max_residual"] <= stats["tolerance"]
    assert stats["redundant_equations"] == ()
    assert 0 < stats["min_pivot_ratio"] <= 1


# ---------------------------------------------------------------------------- four-bar
A4, B4, C4, D4 = 0.2, 0.55, 0.4, 0.6  # crank, coupler, rocker, ground: crank-rocker


def freudenstein(a, b, c, d, th2):
    """Both rocker angles solving Freudenstein's equation
    ``K1 cos th4 - K2 cos th2 + K3 = cos(th2 - th4)``, ``K1 = d/a``, ``K2 = d/c``,
    ``K3 = (a^2 - b^2 + c^2 + d^2)/(2ac)``, via ``t = tan(th4/2)``:
    ``(R - P) t^2 + 2 Q t + (P + R) = 0`` with ``P = cos th2 - K1``, ``Q = sin th2``,
    ``R = K2 cos th2 - K3``."""
    K1, K2, K3 = d / a, d / c, (a**2 - b**2 + c**2 + d**2) / (2 * a * c)
    P, Q, R = np.cos(th2) - K1, np.sin(th2), K2 * np.cos(th2) - K3
    disc = Q**2 + P**2 - R**2
    assert np.all(disc > 0), "the linkage does not close at some crank angle"
    roots = [2 * np.arctan((-Q + sgn * np.sqrt(disc)) / (R - P)) for sgn in (1.0, -1.0)]
    return roots, (K1, K2, K3)


def wrap(angle):
    return (angle + np.pi) % (2 * np.pi) - np.pi


def test_grashof_crank_rocker():
    s, lng = min(A4, B4, C4, D4), max(A4, B4, C4, D4)
    assert s + lng < A4 + B4 + C4 + D4 - s - lng and s == A4


@pytest.fixture(scope="module")
def four_bar_run():
    t = np.linspace(0.0, 2 * np.pi, 97)  # omega = 1: one full crank turn
    return md.kinematic(four_bar(A4, B4, C4, D4, omega=1.0), t)


def test_four_bar_matches_freudenstein(four_bar_run):
    res = four_bar_run
    th2 = res.t
    (r1, r2), (K1, K2, _) = freudenstein(A4, B4, C4, D4, th2)
    th4 = res["rocker.phi"]
    # One circuit all the way round, the one the model starts on.
    e1, e2 = np.abs(wrap(th4 - r1)), np.abs(wrap(th4 - r2))
    branch = r1 if e1[0] < e2[0] else r2
    assert min(e1[0], e2[0]) < 1e-9
    np.testing.assert_allclose(wrap(th4 - branch), 0.0, atol=1e-9)
    # rocker speed and acceleration by implicit differentiation of
    # F(th2, th4) = K1 cos th4 - K2 cos th2 + K3 - cos(th2 - th4) = 0, with th2' = 1
    d = th2 - th4
    F2, F4 = K2 * np.sin(th2) + np.sin(d), -K1 * np.sin(th4) - np.sin(d)
    w4 = -F2 / F4
    F22, F24, F44 = K2 * np.cos(th2) + np.cos(d), -np.cos(d), -K1 * np.cos(th4) + np.cos(d)
    a4 = -(F22 + 2 * F24 * w4 + F44 * w4**2) / F4
    assert_close_rel(res["rocker.omega"], w4, 1e-9)
    assert_close_rel(res["rocker.alpha"], a4, 1e-9)


def test_four_bar_loop_closes(four_bar_run):
    """Crank pin + coupler = ground pivot + rocker, at every time (the vector loop)."""
    res = four_bar_run
    th2, th3, th4 = res.t, res["coupler.phi"], res["rocker.phi"]
    lx = A4 * np.cos(th2) + B4 * np.cos(th3) - D4 - C4 * np.cos(th4)
    ly = A4 * np.sin(th2) + B4 * np.sin(th3) - C4 * np.sin(th4)
    np.testing.assert_allclose(lx, 0.0, atol=1e-12)
    np.testing.assert_allclose(ly, 0.0, atol=1e-12)


# --------------------------------------------------------------- point trajectories
def test_point_velocities_and_accelerations_match_differences():
    """``Result.table(points=...)``: velocities and accelerations of a coupler point against
    five-point differences of its positions over a fine time grid (the solver's own outputs
    at neighbouring times)."""
    h = 1e-3
    centres = np.array([0.4, 1.3, 2.2, 3.7, 5.1])
    offsets = np.array([-2, -1, 0, 1, 2]) * h
    t = (centres[:, None] + offsets[None, :]).ravel()
    res = md.kinematic(four_bar(A4, B4, C4, D4, omega=1.0), t)
    df = res.table(points=["coupler.P", "rocker.B"])
    assert df.attrs["units"]["coupler.P.vx"] == "m/s"
    assert df.attrs["units"]["coupler.P.ay"] == "m/s²"
    for ref in ("coupler.P", "rocker.B"):
        for axis in "xy":
            p = df[f"{ref}.{axis}"].to_numpy().reshape(-1, 5)
            v = df[f"{ref}.v{axis}"].to_numpy().reshape(-1, 5)[:, 2]
            a = df[f"{ref}.a{axis}"].to_numpy().reshape(-1, 5)[:, 2]
            v_fd = (p[:, 0] - 8 * p[:, 1] + 8 * p[:, 3] - p[:, 4]) / (12 * h)
            a_fd = (-p[:, 0] + 16 * p[:, 1] - 30 * p[:, 2] + 16 * p[:, 3] - p[:, 4]) / (12 * h**2)
            np.testing.assert_allclose(v, v_fd, rtol=0, atol=1e-9)
            np.testing.assert_allclose(a, a_fd, rtol=0, atol=1e-6)
    # The position columns are the body frame plus the rotated body-frame offset.
    th3 = df["coupler.phi"].to_numpy()
    px = df["coupler.x"].to_numpy() - np.sin(th3) * B4 / 3
    py = df["coupler.y"].to_numpy() + np.cos(th3) * B4 / 3
    np.testing.assert_allclose(df["coupler.P.x"], px, atol=1e-14)
    np.testing.assert_allclose(df["coupler.P.y"], py, atol=1e-14)


# -------------------------------------------------------------------- redundancy
A_P, L_P, E_P = 0.3, 0.5, 0.2


def test_parallelogram_reports_one_redundant_equation():
    model = parallelogram_with_extra_link(A_P, L_P, E_P)
    report = md.degrees_of_freedom(model)
    assert report.n_coordinates == 12
    assert report.n_equations == 12
    assert report.rank == 11
    assert report.dof == 1
    assert len(report.redundant) == 1
    assert report.redundant[0] in Constraints.of(model).labels[:12]
    assert report.balanced
    # without the extra link: a plain parallelogram four-bar, no redundancy
    plain = md.Model(
        model.bodies[:2] + model.bodies[3:],
        joints=[j for j in model.joints if j.name not in ("O3", "P3")],
        ground=model.ground,
    )
    r2 = md.degrees_of_freedom(plain)
    assert (r2.n_coordinates, r2.rank, r2.dof, r2.redundant) == (9, 8, 1, ())


def check_parallelogram(th_end, linear_solver="auto"):
    """Drive the crank from 30 deg to ``th_end``; the coupler translates on a circle: centre
    ``(L/2 + a cos th, a sin th)``, ``phi = 0``; every link turns with the crank."""
    omega, th0 = 1.0, np.pi / 6
    model = parallelogram_with_extra_link(A_P, L_P, E_P, omega=omega, theta0=th0)
    t = np.linspace(0.0, th_end - th0, 41)
    res = md.kinematic(model, t, linear_solver=linear_solver)
    th = th0 + omega * t
    assert len(res.stats["redundant_equations"]) == 1
    assert linear_solver == "auto" or res.stats["linear_solver"] == linear_solver
    x, y = L_P / 2 + A_P * np.cos(th), A_P * np.sin(th)
    np.testing.assert_allclose(res["coupler.x"], x, atol=1e-12)
    np.testing.assert_allclose(res["coupler.y"], y, atol=1e-12)
    np.testing.assert_allclose(res["coupler.phi"], 0.0, atol=1e-12)
    np.testing.assert_allclose(res["coupler.vx"], -A_P * omega * np.sin(th), atol=1e-12)
    np.testing.assert_allclose(res["coupler.vy"], A_P * omega * np.cos(th), atol=1e-12)
    np.testing.assert_allclose(res["coupler.ax"], -A_P * omega**2 * np.cos(th), atol=1e-11)
    np.testing.assert_allclose(res["coupler.ay"], -A_P * omega**2 * np.sin(th), atol=1e-11)
    for link, x0 in (("follower", L_P), ("extra", E_P)):
        np.testing.assert_allclose(res[f"{link}.phi"], th, atol=1e-12)
        np.testing.assert_allclose(res[f"{link}.omega"], omega, atol=1e-12)
        np.testing.assert_allclose(res[f"{link}.x"], x0 + A_P / 2 * np.cos(th), atol=1e-12)


def test_parallelogram_kinematics_match_closed_form():
    check_parallelogram(np.pi / 3)  # 30 to 60 deg


def test_parallelogram_kinematics_through_vertical_links():
    check_parallelogram(5 * np.pi / 6)  # 30 to 150 deg, through the vertical


@pytest.mark.slow  # long: run by CI's slow set
def test_parallelogram_kinematics_on_the_sparse_path():
    """The redundant equation on the sparse path: the regularized Schur complement."""
    check_parallelogram(5 * np.pi / 6, linear_solver="sparse")


# ---------------------------------------------------------------- compile once
@pytest.fixture
def trace_counter(monkeypatch):
    """Counts evaluations of ``Constraints.full``: every analysis evaluates it only inside
    ``jit``-compiled functions, so the count is the number of traces."""
    calls = {"n": 0}
    original = Constraints.full

    def counting(self, q, t):
        calls["n"] += 1
        return original(self, q, t)

    monkeypatch.setattr(Constraints, "full", counting)
    return calls


def _scan_cache_size():
    scan = importlib.import_module("mixdyn.analysis.kinematic")._kinematic_scan
    cached = getattr(scan, "_cached", None)
    return cached._cache_size() if hasattr(cached, "_cache_size") else None


def test_equal_structures_compile_once(trace_counter):
    t1 = np.linspace(0.0, 1.0, 21)
    t2 = np.linspace(0.5, 2.0, 21)  # same number of output times, other values
    # A driver name used nowhere else: a structure not compiled by another test.
    motor = "motor (compile-once test)"

    def model(r, l, omega):
        return slider_crank(
            r, l, drivers=[md.CoordinateDriver(motor, "crank", "phi", law=md.Ramp(0.0, omega))]
        )

    first = md.kinematic(model(0.1, 0.3, 2.0), t1)
    traced = trace_counter["n"]
    assert traced > 0  # the counter sees the first compilation
    size = _scan_cache_size()
    second = md.kinematic(model(0.12, 0.41, 3.0), t2)
    assert trace_counter["n"] == traced, "a model of equal structure was traced again"
    if size is not None:
        assert _scan_cache_size() == size
    # and the second run used its own numbers
    x, _, _ = slider_closed_form(0.12, 0.41, 3.0, 3.0 * t2)
    assert_close_rel(second["slider.x"], x, 1e-9)
    assert not np.allclose(first["slider.x"], second["slider.x"])


def test_array_slot_axis_is_static_and_compiles_once(trace_counter):
    """A slot axis given as an array is stored as a hashable static value: equal models
    share compiled code (an array there made jit compare static data and fail)."""

    def model(r):
        base = slider_crank(r, 0.3, name="array axis")
        slide = md.Translational("slide", "ground", "slider", axis=np.array([2.0, 0.0]))
        drivers = [md.CoordinateDriver("motor (array axis)", "crank", "phi", law=md.Ramp(0, 1))]
        return base.replace(joints=[*base.joints[:3], slide], drivers=drivers)

    t = np.linspace(0.0, 1.0, 5)
    md.kinematic(model(0.1), t)
    traced = trace_counter["n"]
    res = md.kinematic(model(0.12), t)
    assert trace_counter["n"] == traced
    x, _, _ = slider_closed_form(0.12, 0.3, 1.0, t)
    assert_close_rel(res["slider.x"], x, 1e-9)
