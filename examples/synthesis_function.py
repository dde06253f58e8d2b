"""Four-bar function generation: y = log10(x) for 1 <= x <= 2, against Freudenstein's closed
form.

The crank turns 60 deg from the ground link as x goes from 1 to 2, the rocker turns -60 deg
from 240 deg as y goes from 0 to log10(2). At three Chebyshev precision points Freudenstein's
equation ``K1 cos theta4 - K2 cos theta2 + K3 = cos(theta2 - theta4)`` gives the link ratios
by a 3x3 linear solve; ``md.synthesize`` finds the same four-bar from random starts. With
seven evenly spaced points (more pairs than ratios) it finds the least-squares four-bar, and
the structural error over the range is printed for both.

Run: ``python examples/synthesis_function.py``.
"""

from __future__ import annotations

import numpy as np

import mixdyn as md
from mixdyn.synthesis import FunctionTask

SPANS = {"input_span": np.deg2rad(60.0), "output_span": np.deg2rad(-60.0)}
OUTPUT_START = np.deg2rad(240.0)


def task(points: int, spacing: str) -> FunctionTask:
    return FunctionTask.from_function(
        np.log10, (1.0, 2.0), **SPANS, output_start=OUTPUT_START, points=points, spacing=spacing
    )


def freudenstein(theta2, theta4):
    """Crank, coupler and rocker (ground link 1) through three angle pairs."""
    k = np.linalg.solve(
        np.column_stack([np.cos(theta4), -np.cos(theta2), np.ones(3)]), np.cos(theta2 - theta4)
    )
    a, c = 1 / k[0], 1 / k[1]
    return a, np.sqrt(a * a + c * c + 1 - 2 * a * c * k[2]), c


def structural_error(candidate) -> float:
    """The largest error in y over the range [y's units]."""
    x = np.linspace(1.0, 2.0, 201)
    theta2 = SPANS["input_span"] * (x - 1.0)
    theta4 = candidate.output(theta2, near=OUTPUT_START)
    y = (theta4 - OUTPUT_START) / SPANS["output_span"] * np.log10(2.0)
    return float(np.max(np.abs(y - np.log10(x))))


def main() -> None:
    three = task(3, "chebyshev")
    out = md.synthesize(three, starts=256, seed=0)
    best = out.best
    found = [float(best.linkage.r2), float(best.linkage.r3), float(best.linkage.r4)]
    print("three Chebyshev points, crank, coupler, rocker (ground 1):")
    print("  Freudenstein:", np.round(freudenstein(three.inputs, three.outputs), 10))
    print("  synthesized: ", np.round(found, 10), f"({out.seconds:.1f} s)")
    print(f"  structural error in y: {structural_error(best):.2e}")
    seven = md.synthesize(task(7, "even"), starts=256, seed=0)
    print("seven even points (least squares):", np.round(seven.table().iloc[0, :3].to_numpy(), 6))
    print(f"  structural error in y: {structural_error(seven.best):.2e}")


if __name__ == "__main__":
    main()
