"""The figures of ``mixdyn run`` drawn in a worker process while the runs compute."""

from __future__ import annotations

import contextlib
import os
import pathlib
from typing import ClassVar


class Painter:
    """Draws the figures and animations of ``mixdyn run`` in a worker process
    (:mod:`mixdyn.runtime._worker`: matplotlib, no JAX) while the runs compute, and here where
    no worker can be started or it is lost.

    On Linux the worker forks once it has imported matplotlib and serves two channels, so
    that two figures are drawn at once (an animation beside the plots) for one import: a
    task goes to the channel with the least work queued (an animation counts as
    :data:`MOVIE_COST` plots).

    :meth:`draw` hands over a task, :meth:`done` a file already written (to keep the order),
    :meth:`results` waits for all of them in order and raises the first failure.
    """

    #: An animation's drawing time in plots (the paper's example: 81 frames ~0.5 s, a
    #: plot ~0.1 s, measured in the worker of a warm run).
    MOVIE_COST = 5
    #: The drawing time of a task of each kind, in plots (1 where not given).
    COSTS: ClassVar[dict[str, int]] = {"movie": MOVIE_COST}

    def __init__(self):
        import tempfile

        from ..runtime import _command

        self.tasks: list = []  # (task or None, path or None, channel or None)
        self.tmp = tempfile.mkdtemp(prefix="mixdyn-figures-")
        self.channels: list = []  # (tasks writer, replies reader) or None where lost
        self.proc, second = _command.worker()  # started with the command where it could be
        if self.proc is None:
            return
        self.channels.append((self.proc.stdin, self.proc.stdout))
        if second is not None:
            writer = open(second[0], "w", encoding="utf-8")  # noqa: SIM115 - closed in close()
            self.channels.append((writer, open(second[1], encoding="utf-8")))  # noqa: SIM115
        self.queued = [0] * len(self.channels)

    def draw(self, kind: str, *args, **kwargs) -> None:
        import pickle

        task = (kind, args, kwargs)
        live = [k for k, c in enumerate(self.channels) if c is not None]
        if live:
            k = min(live, key=lambda i: self.queued[i])
            name = os.path.join(self.tmp, f"task{len(self.tasks)}.pickle")
            try:
                with open(name, "wb") as f:
                    pickle.dump(task, f, protocol=pickle.HIGHEST_PROTOCOL)
                self.channels[k][0].write(name + "\n")
                self.channels[k][0].flush()
                self.queued[k] += self.COSTS.get(kind, 1)
                self.tasks.append((task, None, k))
                return
            except (OSError, ValueError, pickle.PicklingError):
                self._lose(k)
        self.tasks.append((task, None, None))

    def done(self, path) -> None:
        self.tasks.append((None, path, None))

    def results(self) -> list[pathlib.Path]:
        import pickle

        out = []
        tasks, self.tasks = self.tasks, []
        for task, path, k in tasks:
            if task is None:
                out.append(path)
                continue
            reply = None
            if k is not None and self.channels[k] is not None:
                line = self.channels[k][1].readline()
                if line.strip():
                    reply = pickle.loads(bytes.fromhex(line.strip()))
                else:
                    self._lose(k)
            if reply is None:  # no worker: drawn here
                out.append(draw_here(*task))
                continue
            status, value = reply
            if status == "error":
                raise value
            out.append(pathlib.Path(value))
        return out

    def _drop(self, k: int) -> None:
        """Close channel ``k`` (the end of its tasks: the copy serving it ends)."""
        for end in self.channels[k] or ():
            with contextlib.suppress(OSError, ValueError):
                end.close()
        self.channels[k] = None

    def _lose(self, k: int) -> None:
        """Give up channel ``k`` (its tasks are drawn here); the worker with the last one."""
        self._drop(k)
        if not any(self.channels):
            self._stop()

    def _stop(self) -> None:
        """Stop the worker (and its copy) at once."""
        from ..runtime import _command

        if self.proc is not None:
            _command.stop(self.proc)
            self.proc = None

    def abort(self) -> None:
        """Close without waiting for the worker (it may still be importing): for a run that
        has nothing for it to draw."""
        self._stop()
        self.close()

    def close(self) -> None:
        import shutil
        import subprocess

        for k in range(len(self.channels)):
            self._drop(k)
        if self.proc is not None:
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._stop()
            self.proc = None
        shutil.rmtree(self.tmp, ignore_errors=True)


def draw_here(kind: str, args, kwargs) -> pathlib.Path:
    """Draw task ``(kind, args, kwargs)`` in this process, as the worker draws it."""
    from . import _draw, sweep_plots, synthesis_plots
    from .plots import plot_columns

    do = {
        "plot": plot_columns,
        "movie": _draw.movie,
        "against": sweep_plots.plot_against,
        "band": sweep_plots.plot_band,
        "fit": sweep_plots.plot_fit,
        "optimum": sweep_plots.plot_optimum,
        "synthesis": synthesis_plots.plot_synthesis,
    }
    return do[kind](*args, **kwargs)


__all__ = ["Painter", "draw_here"]
