"""Cost of a reverse-mode gradient against the run itself: the paper's model (forward, 2 s,
201 outputs, rtol 1e-8), the objective the RMS of the slider's x over the outputs, with
respect to 11 numbers (the four bodies' masses and inertias, F1's amplitude, T2 and T3).

Both jitted and warm; best of ``--repeat``. Prints the ratio gradient / run, and checks the
gradient against central finite differences of the jitted run (relative step 1e-6).

Run: ``python benchmarks/gradient.py [--repeat 5]``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

import mixdyn as md
from fixtures import paper_under_loads

PARAMS = [
    *(f"{b}.{f}" for b in ("crank", "coupler", "link", "slider") for f in ("mass", "inertia")),
    "F1.law.amplitude",
    "T2.law.value",
    "T3.law.value",
]


def best(fn, repeat):
    jax.block_until_ready(fn())
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        out.append(time.perf_counter() - t0)
    return min(out)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--max-steps", type=int, default=1_000_000)
    a = ap.parse_args()
    model = paper_under_loads()
    run = md.analyses.Forward(method=md.Projection(rtol=1e-8, max_steps=a.max_steps))
    f, th0 = md.differentiable(model, np.linspace(0.0, 2.0, 201), PARAMS, analysis=run)
    ix = 3 * 3  # the slider's x

    def objective(th):
        return jnp.sqrt(jnp.mean(f(th)["q"][:, ix] ** 2))

    run, grad = jax.jit(objective), jax.jit(jax.grad(objective))
    t_run, t_grad = best(lambda: run(th0), a.repeat), best(lambda: grad(th0), a.repeat)
    g = np.asarray(grad(th0))
    fd = []
    for k in range(len(th0)):
        h = 1e-6 * abs(th0[k])
        e = np.zeros_like(th0)
        e[k] = h
        fd.append((float(run(th0 + e)) - float(run(th0 - e))) / (2 * h))
    fd = np.asarray(fd)
    # relative to each entry, floored at 1e-6 of the largest (the slider's inertia has none)
    rel = np.max(np.abs(g - fd) / np.maximum(np.abs(fd), 1e-6 * np.max(np.abs(fd))))
    print(f"{len(PARAMS)} parameters; run {1e3 * t_run:.1f} ms, gradient {1e3 * t_grad:.1f} ms")
    print(f"gradient / run = {t_grad / t_run:.2f}; largest relative difference to FD {rel:.1e}")


if __name__ == "__main__":
    main()
