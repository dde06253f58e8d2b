"""Four-bar path generation with the motor torque in the objective, written as a model file.

Five points of a closed curve [m], timing-free; bars of 2 kg/m with a 0.5 kg payload at the
coupler point, the crank at one turn a second under gravity. ``md.synthesize`` refines 256
random starts by Levenberg-Marquardt at once (the score: the path error plus 1e-4 m^2/(N m)^2
times the RMS motor torque squared), then writes the best four-bar as ``synthesis_best.yaml``:
a kinematic run (the coupler point's path) and an inverse run (the motor torque) that
``mixdyn run`` runs.

Run: ``python examples/synthesis_path.py [folder]``, then
``mixdyn run folder/synthesis_best.yaml --out folder/runs``.
"""

from __future__ import annotations

import pathlib
import sys

import numpy as np

import mixdyn as md
from mixdyn.synthesis import Masses, Objective, PathTask

POINTS = np.array([[0.50, 0.30], [0.58, 0.42], [0.48, 0.55], [0.32, 0.50], [0.30, 0.36]])


def main(folder: pathlib.Path) -> md.synthesis.Synthesis:
    objective = Objective(
        masses=Masses(density=2.0, payload=0.5), speed=2 * np.pi, torque_weight=1e-4
    )

    def progress(stage, done, total, best):
        print(f"{stage}: {done}/{total} starts, best score {best:.3e}", flush=True)

    out = md.synthesize(PathTask(POINTS), objective, starts=256, seed=0, progress=progress)
    print(out.table()[["r1", "r2", "r3", "r4", "error", "torque_rms", "torque_peak"]].head())
    folder.mkdir(parents=True, exist_ok=True)
    out.write(folder / "synthesis_best.yaml")
    print(f"wrote {folder / 'synthesis_best.yaml'} ({out.seconds:.0f} s, {out.feasible} feasible)")
    return out


if __name__ == "__main__":
    main(pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "."))
