"""The HTML player against plotly's animation frames, on the paper's example (201 outputs).

Both pages show the same motion (every body's outline at every output time); the script
prints each page's size and the time headless Chromium takes to load it and run its script
(``--dump-dom`` until the page is idle; the median of five), and their ratios. plotly is
not a dependency of mixdyn: ``pip install plotly`` to run this.

    python benchmarks/player.py
"""

from __future__ import annotations

import pathlib
import shutil
import statistics
import subprocess
import tempfile
import time

import numpy as np

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--window-size=1000,800",
]


def plotly_page(scene, times, path) -> pathlib.Path:
    """The motion as plotly frames: a filled outline trace per body, a slider and play."""
    import plotly.graph_objects as go

    def traces(i):
        return [
            go.Scatter(
                x=np.append(o[i, :, 0], o[i, 0, 0]),
                y=np.append(o[i, :, 1], o[i, 0, 1]),
                fill="toself",
                mode="lines",
                name=name,
            )
            for name, o in zip(scene.names, scene.outlines, strict=True)
        ]

    frames = [go.Frame(data=traces(i), name=f"{t:.3f}") for i, t in enumerate(times)]
    fig = go.Figure(data=traces(0), frames=frames)
    fig.update_layout(
        yaxis={"scaleanchor": "x"},
        updatemenus=[
            {"type": "buttons", "buttons": [{"label": "Play", "method": "animate", "args": [None]}]}
        ],
        sliders=[
            {
                "steps": [
                    {
                        "method": "animate",
                        "label": f.name,
                        "args": [[f.name], {"mode": "immediate"}],
                    }
                    for f in frames
                ]
            }
        ],
    )
    fig.write_html(path, include_plotlyjs=True, full_html=True)
    return pathlib.Path(path)


def load_seconds(page: pathlib.Path, runs: int = 5) -> float:
    chromium = shutil.which("chromium") or shutil.which("google-chrome")
    out = []
    for _ in range(runs):
        with tempfile.TemporaryDirectory() as profile:
            t0 = time.perf_counter()
            subprocess.run(
                [
                    chromium,
                    *FLAGS,
                    f"--user-data-dir={profile}",
                    "--dump-dom",
                    page.as_uri() + "#t=1",
                ],
                capture_output=True,
                check=True,
                timeout=120,
            )
            out.append(time.perf_counter() - t0)
    return statistics.median(out)


def main() -> None:
    import mixdyn as md
    import mixdyn.io as mio
    import mixdyn.runs
    from mixdyn.viz import Scene, html

    root = pathlib.Path(__file__).resolve().parent.parent
    spec = mio.read(root / "examples" / "antonya.yaml")
    res = mixdyn.runs.execute(spec, ["forward"])["forward"]
    with tempfile.TemporaryDirectory() as d:
        ours = html(res, pathlib.Path(d) / "mixdyn.html", trace=["coupler.C"])
        scene = Scene(res.model, np.asarray(res.q))
        theirs = plotly_page(scene, res.t, pathlib.Path(d) / "plotly.html")
        a, b = ours.stat().st_size, theirs.stat().st_size
        print(f"frames: {len(res.t)} (mixdyn {md.__version__})")
        print(f"page size: mixdyn {a / 1e3:.0f} kB, plotly {b / 1e3:.0f} kB, ratio {b / a:.1f}")
        if shutil.which("chromium") or shutil.which("google-chrome"):
            ta, tb = load_seconds(ours), load_seconds(theirs)
            print(
                f"headless Chromium load + script: mixdyn {ta:.2f} s, plotly {tb:.2f} s, "
                f"ratio {tb / ta:.2f}"
            )
        else:
            print("no Chromium here: load times not measured")


if __name__ == "__main__":
    main()
