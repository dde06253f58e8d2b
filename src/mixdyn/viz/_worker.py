"""A process that draws figures and animations for ``mixdyn run`` while it computes.

Run as a script (``python .../mixdyn/viz/_worker.py``): it imports neither mixdyn nor JAX,
only NumPy, matplotlib and Pillow, and loads :mod:`mixdyn.viz.plots` and
:mod:`mixdyn.viz._draw` by their paths. Each line on standard input names a file holding a
pickled task ``(kind, args, kwargs)`` (``kind``: ``"plot"``, ``"movie"``, ``"against"`` or
``"band"``); for each it
writes one line on standard output, the hex of a pickled ``("ok", path)`` or
``("error", exception)``. An empty line or the end of the input ends it.
"""

from __future__ import annotations

import importlib.util
import os
import pathlib
import pickle
import sys


def _load(name: str):
    path = pathlib.Path(__file__).with_name(f"{name}.py")
    spec = importlib.util.spec_from_file_location(f"_mixdyn_worker_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main() -> None:
    plots, draw, sweeps = _load("plots"), _load("_draw"), _load("sweep_plots")
    from matplotlib.figure import Figure

    Figure()  # matplotlib reads its settings and fonts once, before the first task
    do = {
        "plot": plots.plot_columns,
        "movie": draw.movie,
        "against": sweeps.plot_against,
        "band": sweeps.plot_band,
        "fit": sweeps.plot_fit,
        "optimum": sweeps.plot_optimum,
    }
    for line in sys.stdin:
        name = line.strip()
        if not name:
            break
        try:
            with open(name, "rb") as f:
                kind, args, kwargs = pickle.load(f)
            os.unlink(name)
            reply = ("ok", str(do[kind](*args, **kwargs)))
        except Exception as e:
            try:
                pickle.dumps(e)
            except Exception:
                e = RuntimeError(f"{type(e).__name__}: {e}")
            reply = ("error", e)
        sys.stdout.write(pickle.dumps(reply).hex() + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
    sys.stdout.flush()
    os._exit(0)  # every reply is written: skip the interpreter's slow tear-down of matplotlib
