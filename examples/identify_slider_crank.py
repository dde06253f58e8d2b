"""Parameter identification: the slider's and the rod's masses, the rod's inertia and a damper's
coefficient of a slider–crank, recovered from a noisy recorded motion (SI units).

The "recording" is a forward run at the true numbers (a harmonic motor torque on the crank, a
spring–damper pulling the slider towards the ground point P) with Gaussian noise on the
slider's x (0.1 mm) and the crank angle (1 mrad) at 101 times over 2 s. ``md.fit`` solves the
weighted least-squares problem (scipy's ``least_squares``) with the Jacobian from forward-mode
differentiation of the run (``jax.jacfwd`` through the integrator). The standard deviations
come from the Jacobian at the optimum (``(J^T J)^-1`` of the weighted residuals); each estimate
is printed with its distance from the truth in those deviations.

Run: ``python examples/identify_slider_crank.py [--seed 0]``; ``--write FILE.csv`` writes the
recording instead (``examples/data/slider_crank_recording.csv``: seed 0, read by
``examples/identify_slider_crank.yaml``).
"""

from __future__ import annotations

import argparse

import numpy as np

import mixdyn as md

#: The identified numbers (paths into the model) and their true values (kg, kg, kg m^2, N s/m).
PARAMS = ["slider.mass", "rod.mass", "rod.inertia", "damper.damping"]
TRUE = np.array([1.0, 1.0, 0.01, 2.0])
#: Noise of the recording: slider x [m], crank angle [rad].
NOISE = (1e-4, 1e-3)
#: q indices of the slider's x and the crank's angle.
SLIDER_X, CRANK_PHI = 6, 2


def build_model() -> md.Model:
    """An in-line slider–crank (crank 0.1 m, rod 0.3 m), a motor torque 3 sin(4 t) N m on the
    crank and a spring–damper (200 N/m, free length 0.4 m) from the ground point P to the
    slider, at the true numbers."""
    r, l = 0.1, 0.3
    return md.Model(
        bodies=[
            md.Body(
                "crank", 1.0, 0.01, q0=(r / 2, 0, 0), points={"O": (-r / 2, 0), "A": (r / 2, 0)}
            ),
            md.Body(
                "rod",
                TRUE[1],
                TRUE[2],
                q0=(r + l / 2, 0, 0),
                points={"A": (-l / 2, 0), "B": (l / 2, 0)},
            ),
            md.Body("slider", TRUE[0], 0.01, q0=(r + l, 0, 0)),
        ],
        joints=[
            md.Revolute("O", "ground", "crank.O"),
            md.Revolute("A", "crank.A", "rod.A"),
            md.Revolute("B", "rod.B", "slider"),
            md.Translational("slide", "ground", "slider", axis=(1, 0)),
        ],
        forces=[
            md.Torque("motor", "crank", law=md.Harmonic(3.0, 4.0)),
            md.SpringDamper(
                "damper", "ground", "slider", stiffness=200.0, damping=TRUE[3], free_length=0.4
            ),
        ],
        units=md.SI,
        name="slider-crank-identification",
    )


def record(seed: int = 0):
    """The "recording": ``(t, {"slider.x": (101,), "crank.phi": (101,)})``, the true run
    with noise (:data:`NOISE`) drawn from ``numpy.random.default_rng(seed)``."""
    t = np.linspace(0.0, 2.0, 101)
    truth = np.asarray(md.forward(build_model(), t, rtol=1e-10, atol=1e-12).q)
    rng = np.random.default_rng(seed)
    measured = {
        name: truth[:, k] + s * rng.standard_normal(len(t))
        for name, k, s in zip(("slider.x", "crank.phi"), (SLIDER_X, CRANK_PHI), NOISE, strict=True)
    }
    return t, measured


def identify(seed: int = 0, start=(1.3, 0.7, 1.4, 0.6)):
    """Record, then fit from ``TRUE * start`` (:func:`mixdyn.fit`). Returns ``(estimate,
    deviations, truth, reduced chi-square)``, each (4,) but the last."""
    t, measured = record(seed)
    model = build_model()
    result = md.fit(
        model,
        t,
        measured,
        PARAMS,
        noise=dict(zip(measured, NOISE, strict=True)),
        start=TRUE * np.asarray(start),
        analysis=md.analyses.Forward(method=md.Projection(rtol=1e-10, atol=1e-12)),
    )
    return result.values, result.deviations, TRUE, result.chi2


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--write", metavar="CSV", help="write the recording to CSV and stop")
    a = ap.parse_args()
    seed = a.seed
    if a.write:
        t, measured = record(seed)
        with open(a.write, "w", encoding="utf-8") as f:
            f.write("t,x,phi\n")
            for row in zip(t, measured["slider.x"], measured["crank.phi"], strict=True):
                f.write(",".join(f"{v:.17g}" for v in row) + "\n")
        return
    est, sd, truth, chi2 = identify(seed)
    print(f"{'number':16} {'true':>10} {'estimate':>12} {'std. dev.':>10} {'off by':>8}")
    for name, x0, x, s in zip(PARAMS, truth, est, sd, strict=True):
        print(f"{name:16} {x0:10.5g} {x:12.6g} {s:10.2g} {(x - x0) / s:7.2f} sd")
    print(f"reduced chi-square of the fit: {chi2:.3f} (1 when the model explains the noise)")


if __name__ == "__main__":
    main()
