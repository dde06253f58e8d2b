"""Drawing an animation from plain data (NumPy arrays and strings), with matplotlib's Agg
canvas and Pillow.

This module imports nothing from mixdyn (nor JAX), so that a process that only draws
(:mod:`mixdyn.runtime._worker`) can load it by its path; :func:`mixdyn.viz.animate` builds the
data (:func:`mixdyn.viz.animate.movie_data`) and calls :func:`movie`.
"""

from __future__ import annotations

import contextlib
import pathlib

import numpy as np

#: The context a GIF whose frames share one palette is written in: none here; the figure
#: worker of ``mixdyn run`` (:mod:`mixdyn.runtime._worker`) gives it
#: :func:`mixdyn.runtime._private.shared_palette`.
GIF_CONTEXT = contextlib.nullcontext

COLORS = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#7f7f7f",
    "#bcbd22",
    "#17becf",
)


#: Line widths of the symbols by kind (:mod:`mixdyn.viz.symbols`).
SYMBOL_WIDTH = {"spring": 1.2, "damper": 1.4, "spring_damper": 1.2, "rotary_spring": 1.2,
                "torque": 2.0, "force": 2.2}  # fmt: skip


def body_style(color: str, closed: bool) -> dict:
    """A body's patch style: a plate (closed outline) translucent, so that a body beneath it
    (a crank under a triangular coupler) shows through; a bar as a thick line."""
    from matplotlib.colors import to_rgba

    if closed:
        return {"fc": to_rgba(color, 0.22), "ec": color, "lw": 1.8}
    return {"fc": "none", "ec": to_rgba(color, 0.9), "lw": 3.0}


def legend(ax) -> None:
    """The legend beside the axes (right of them), never over the mechanism."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                  fontsize="small", frameon=False)  # fmt: skip


def movie(data: dict, path, *, fps: int = 20, size=None, dpi: int = 100) -> pathlib.Path:
    """Write the animation ``data`` (see :func:`mixdyn.viz.animate.movie_data`) to ``path``:
    ``.gif`` (Pillow) or ``.mp4`` (ffmpeg).

    Returns:
        The path written.
    """
    from matplotlib import animation
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon

    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    outlines, names = data["outlines"], data["names"]
    pins_xy, ground, guides, traces = data["pins"], data["ground"], data["guides"], data["traces"]
    times = np.asarray(data["times"])
    x0, x1, y0, y1 = data["bounds"]
    if size is None:
        aspect = (y1 - y0) / max(x1 - x0, 1e-12)
        size = (6.4, float(np.clip(6.4 * aspect + 0.9, 3.0, 7.0)))
    fig = Figure(figsize=size, dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.25)
    u = data["length_unit"]
    ax.set_xlabel(f"x [{u}]")
    ax.set_ylabel(f"y [{u}]")
    for g in guides:
        ax.plot(g[:, 0], g[:, 1], color="0.55", lw=1.0, ls="-.", zorder=1)
    if len(ground):
        ax.plot(ground[:, 0], ground[:, 1], "^", color="0.3", ms=9, zorder=2)
    patches = []
    for k, outline in enumerate(outlines):
        color = COLORS[k % len(COLORS)]
        closed = outline.shape[1] > 2
        patch = Polygon(
            outline[0], closed=closed, zorder=3, label=names[k], **body_style(color, closed)
        )
        ax.add_patch(patch)
        patches.append(patch)
    symbols = data.get("symbols", [])
    symbol_lines = [
        ax.plot(
            [],
            [],
            "-",
            color=m["color"],
            lw=SYMBOL_WIDTH[m["kind"]],
            zorder=4,
            label=m["label"] if m["kind"] in ("torque", "force") else None,
        )[0]
        for m in symbols
    ]
    (pins,) = ax.plot([], [], "o", mfc="white", mec="k", ms=6, zorder=5)
    trace_lines = [ax.plot([], [], "-", lw=1.0, color="k", alpha=0.6, zorder=4)[0] for _ in traces]
    arrows = data.get("arrows", [])
    quiver = None
    if arrows:
        at = np.stack([a["at"] for a in arrows], axis=1)  # (F, A, 2)
        vec = np.stack([a["v"] for a in arrows], axis=1)
        quiver = ax.quiver(
            at[0, :, 0],
            at[0, :, 1],
            vec[0, :, 0],
            vec[0, :, 1],
            angles="xy",
            scale_units="xy",
            scale=1.0,
            color=[a["color"] for a in arrows],
            width=0.006,
            zorder=6,
        )
        for a in arrows:
            ax.plot([], [], color=a["color"], lw=2.5, label=a["name"])
        ax.text(0.02, 0.02, data.get("arrow_note", ""), transform=ax.transAxes, fontsize=8)
    label = ax.text(0.02, 0.96, "", transform=ax.transAxes, va="top", fontsize=9)
    ax.set_title(data["title"])
    legend(ax)
    tu = data["time_unit"]

    def draw(i):
        for patch, outline in zip(patches, outlines, strict=True):
            patch.set_xy(outline[i])
        if pins_xy.shape[1]:
            pins.set_data(pins_xy[i, :, 0], pins_xy[i, :, 1])
        for line, tr in zip(trace_lines, traces, strict=True):
            line.set_data(tr[: i + 1, 0], tr[: i + 1, 1])
        for line, m in zip(symbol_lines, symbols, strict=True):
            line.set_data(m["path"][i, :, 0], m["path"][i, :, 1])
        label.set_text(f"t = {times[i]:.3f} {tu}")
        if quiver is not None:
            quiver.set_offsets(at[i])
            quiver.set_UVC(vec[i, :, 0], vec[i, :, 1])
            return [*patches, *symbol_lines, pins, *trace_lines, quiver, label]
        return [*patches, *symbol_lines, pins, *trace_lines, label]

    # Lay the figure out once, then keep that layout for every frame.
    draw(0)
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".mp4":
        anim = animation.FuncAnimation(fig, draw, frames=len(times), blit=False, repeat=False)
        anim.save(str(path), writer=animation.FFMpegWriter(fps=fps), dpi=fig.dpi)
        return path
    # GIF: draw the still parts once and only the moving ones per frame (blitting).
    moving = draw(0)
    for a in moving:
        a.set_animated(True)
    canvas = fig.canvas
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    writer = _gif_writer(fps)
    # One palette for every frame, from the last one (every body, the whole trace): mapping
    # a frame onto it costs a quarter of quantizing each frame anew.
    canvas.restore_region(background)
    for a in draw(len(times) - 1):
        ax.draw_artist(a)
    writer.palette = writer.reduce(canvas)
    with writer.saving(fig, str(path), dpi=fig.dpi):
        for i in range(len(times)):
            canvas.restore_region(background)
            for a in draw(i):
                ax.draw_artist(a)
            writer.grab_frame()
    return path


def _gif_writer(fps: int):
    from matplotlib import animation
    from PIL import Image

    class GifWriter(animation.PillowWriter):
        """matplotlib's PillowWriter, taking each frame from the Agg canvas as drawn (no
        re-rendering) and mapping it onto one palette (:attr:`palette`, from
        :meth:`reduce`; without one each frame is quantized on its own)."""

        palette = None

        @staticmethod
        def reduce(canvas):
            rgb = Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba())
            return rgb.convert("RGB").quantize(colors=128, method=Image.Quantize.FASTOCTREE)

        def finish(self):
            # Every frame has the one palette: written in GIF_CONTEXT (in the command's
            # figure worker, Pillow then keeps it rather than remapping each frame).
            if self.palette is None:
                return super().finish()
            with GIF_CONTEXT():
                super().finish()

        def grab_frame(self, **savefig_kwargs):
            canvas = self.fig.canvas
            if self.palette is None:
                self._frames.append(self.reduce(canvas))
                return
            rgb = Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba())
            frame = rgb.convert("RGB").quantize(palette=self.palette, dither=Image.Dither.NONE)
            self._frames.append(frame)

    return GifWriter(fps=fps)
