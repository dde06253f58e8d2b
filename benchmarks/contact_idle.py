"""What a contact costs where it never touches: the paper's example with a contact pair out of
reach, against the same run without it, in one process.

The model is ``examples/antonya.yaml`` (four moving bodies, mm-kg-s) and its forward run
(``projection``, rtol = atol = 1e-10, 201 outputs over 2 s). Three variants:

- ``none``: the model as it is;
- ``compliant``: a ``circle_line_contact`` between a 5 mm disc on the slider and a ground line
  500 mm below it (steel, Lankarani-Nikravesh, restitution 0.9): its force is evaluated at
  every stage (zero: the gap is open), its broad phase skips the narrow one;
- ``rigid``: the same pair with ``contact_model: rigid``: the run is integrated from impact to
  impact by the events' path (:mod:`mixdyn.analysis._impacts`), here one segment.

Each is prepared once (:func:`mixdyn.prepare`) and run ``--repeat`` times (:func:`mixdyn.run`,
the whole run: integration, outputs and checks); the table gives the best CPU and wall time
and the ratio to ``none``, and the largest difference of the bodies' coordinates from
``none``'s (the contact takes no part, so the motion must be the same). Compile times are
the first run's. Run pinned to one core for stable CPU figures (``taskset -c 0``).

    python benchmarks/contact_idle.py [--repeat 15]
"""

from __future__ import annotations

import argparse
import pathlib
import time

import numpy as np

import mixdyn as md
from mixdyn.io.load import build, reads

ROOT = pathlib.Path(__file__).resolve().parents[1]
PAPER = ROOT / "examples" / "antonya.yaml"

#: The contact pair added, out of reach (model units: mm, kg, s), with the law of each variant.
PAIR = (
    "  - {{type: circle_line_contact, name: stop, center: slider, radius: 5,\n"
    "     line_point: ground.S, {law}}}\n"
)
LAWS = {
    "compliant": "young_modulus: 207 GPa, restitution: 0.9, impact_speed: 100 mm/s",
    "rigid": "contact_model: rigid, restitution: 0.9",
}


def model_text(variant: str) -> str:
    """The paper's model file with the contact of ``variant`` (``none``: as it is)."""
    text = PAPER.read_text()
    if variant == "none":
        return text
    text = text.replace("    F: [100, 6.6987]\n", "    F: [100, 6.6987]\n    S: [0, -500]\n")
    pair = PAIR.format(law=LAWS[variant])
    return text.replace("\n# The start:", "\n" + pair + "\n# The start:", 1)


def measure(variant: str, repeat: int) -> dict:
    model = build(reads(model_text(variant), f"<{variant}>"))
    analysis = md.analyses.Forward(
        method=md.Projection(rtol=1e-10, atol=1e-10), hold=["crank.phi", "coupler.phi"]
    )
    ts = np.linspace(0.0, 2.0, 201)
    t0 = time.perf_counter()
    setup = md.prepare(model, analysis)
    r = md.run(setup, ts)
    first = time.perf_counter() - t0
    cpu, wall = [], []
    for _ in range(repeat):
        c, w = time.process_time(), time.perf_counter()
        r = md.run(setup, ts)
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - w)
    return {
        "variant": variant,
        "first_s": first,
        "cpu_ms": 1e3 * min(cpu),
        "wall_ms": 1e3 * min(wall),
        "steps": int(r.stats["steps"]),
        "q": np.asarray(r.q),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    args = ap.parse_args()
    rows = [measure(v, args.repeat) for v in ("none", "compliant", "rigid")]
    base = rows[0]
    print("| contact | first run [s] | run CPU [ms] | run wall [ms] | CPU / none | steps |"
          " max coordinate difference to none |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        diff = float(np.max(np.abs(r["q"] - base["q"])))
        print(
            f"| {r['variant']} | {r['first_s']:.1f} | {r['cpu_ms']:.1f} | {r['wall_ms']:.1f} | "
            f"{r['cpu_ms'] / base['cpu_ms']:.2f} | {r['steps']} | {diff:.1e} |"
        )


if __name__ == "__main__":
    main()
