"""Slider–crank driven at constant crank speed: kinematics compared with the closed form."""

import numpy as np

import mixdyn as md

r, l = 0.1, 0.3  # crank and rod lengths [m]
model = md.Model(
    bodies=[
        md.Body("crank", 1.0, 0.01, q0=(0.05, 0, 0), points={"O": (-0.05, 0), "A": (0.05, 0)}),
        md.Body("rod", 1.0, 0.01, q0=(0.25, 0, 0), points={"A": (-0.15, 0), "B": (0.15, 0)}),
        md.Body("slider", 1.0, 0.01, q0=(0.4, 0, 0)),
    ],
    joints=[
        md.Revolute("O", "ground", "crank.O"),
        md.Revolute("A", "crank.A", "rod.A"),
        md.Revolute("B", "rod.B", "slider"),
        md.Translational("slide", "ground", "slider", axis=(1, 0)),
    ],
    drivers=[md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(0.0, 2.0))],
    units=md.SI,
    name="slider-crank",
)

if __name__ == "__main__":
    t = np.linspace(0.0, np.pi, 181)
    res = md.kinematic(model, t)
    th = 2.0 * t
    exact = r * np.cos(th) + np.sqrt(l**2 - (r * np.sin(th)) ** 2)
    print(model.summary())
    print(md.degrees_of_freedom(model))
    err = np.max(np.abs(res["slider.x"] - exact))
    print(f"largest slider position error vs closed form: {err:.2e} m")
