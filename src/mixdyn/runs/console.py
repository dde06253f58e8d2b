"""What ``mixdyn`` shows on the terminal besides its results: text made safe for it and
printed (:func:`say`), and the progress of ``mixdyn run`` (a bar or a line per run, or a plain
line every few seconds off a terminal, and the notice of its first compile off a terminal)."""

from __future__ import annotations

import re
import sys
import time
from collections.abc import Callable

from .kinds import kind_of

#: Characters never sent to the terminal as they are: C0 and C1 controls (escape sequences),
#: DEL, and the bidirectional overrides that reorder what is shown.
_CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")

#: Seconds between two progress lines when stderr is not a terminal.
PROGRESS_LOG_EVERY = 5.0


def clean(text) -> str:
    """``text`` with every control character (except newlines and tabs) shown as an escape
    (``\\x1b``), so that names and paths from a file cannot drive the terminal."""
    return _CONTROL.sub(lambda m: ascii(m.group())[1:-1], str(text))


def esc(text) -> str:
    """User text (names, paths) made safe inside rich markup and on the terminal."""
    from rich.markup import escape

    return escape(clean(text))


def say(text: str = "") -> None:
    """Print ``text`` (rich markup) on stdout, its control characters made harmless."""
    from rich.console import Console

    Console(soft_wrap=True, highlight=False).print(clean(text))


def compiling(file) -> None:
    """The one line ``mixdyn run`` writes off a terminal as it first compiles (on stdout,
    beside the files written: stderr holds a failure's one line alone)."""
    sys.stdout.write(
        f"{clean(file)}: compiling the model's programs (the first time for this model, "
        "up to a minute; later runs read them from the cache)\n"
    )
    sys.stdout.flush()


def progress_log(plan, every: float = PROGRESS_LOG_EVERY) -> Callable:
    """A progress callback ``f(t)`` writing a plain line on stderr at most every ``every``
    seconds: the run, the simulated time, the fraction done and the time elapsed."""
    t0, t1 = float(plan.times[0]), float(plan.times[-1])
    start = time.monotonic()
    last = [start]

    def at(t):
        now = time.monotonic()
        if now - last[0] < every:
            return
        last[0] = now
        done = (float(t) - t0) / ((t1 - t0) or 1.0)
        sys.stderr.write(
            clean(
                f"{plan.name}: t = {float(t):.6g} of {t1:.6g} ({100 * done:.0f}%), "
                f"{now - start:.0f} s\n"
            )
        )
        sys.stderr.flush()

    return at


def members_log(plan, every: float = PROGRESS_LOG_EVERY) -> Callable:
    """A per-member progress callback writing a plain line on stderr at most every ``every``
    seconds: the sweep, the members done and the time elapsed."""
    import threading

    start = time.monotonic()
    state = {"last": start, "done": 0}
    lock = threading.Lock()

    def at(i):
        with lock:
            state["done"] += 1
            now = time.monotonic()
            if now - state["last"] < every and state["done"] < plan.members:
                return
            state["last"] = now
            sys.stderr.write(
                clean(f"{plan.name}: {state['done']} of {plan.members} members, ")
                + f"{now - start:.0f} s\n"
            )
            sys.stderr.flush()

    return at


class RunProgress:
    """The progress of ``mixdyn run``'s runs on stderr, a task per run (its label and total
    from its kind: :meth:`.kinds.RunKind.task`).

    Args:
        plans: the runs, in the order they run.
        mode: ``"off"``, ``"runs"`` (a line per run), ``"steps"`` (a bar following the
            simulated time; off a terminal a plain line every few seconds instead, ``"log"``).

    Use as a context manager; :meth:`hook` gives a run's callback (:meth:`.kinds.RunKind.progress`,
    which asks for :meth:`times` or :meth:`members`).
    """

    def __init__(self, plans, mode: str):
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            Progress,
            SpinnerColumn,
            TaskProgressColumn,
            TextColumn,
            TimeElapsedColumn,
        )

        self.console = Console(stderr=True)
        if mode == "steps" and not self.console.is_terminal:
            mode = "log"  # no bar off a terminal: a plain line every few seconds instead
        self.mode = mode
        columns = (
            SpinnerColumn(),
            TextColumn("{task.description}"),
            BarColumn(),
            TaskProgressColumn(),
            TimeElapsedColumn(),
        )
        disable = mode in ("off", "log")
        self.bar = Progress(*columns, console=self.console, disable=disable, transient=False)
        self.plans = list(plans)
        self.tasks: dict = {}

    def __enter__(self) -> RunProgress:
        self.bar.__enter__()
        for plan in self.plans:
            label, total = kind_of(plan).task(plan, self.mode)
            self.tasks[plan.name] = self.bar.add_task(label, total=total, start=False)
        return self

    def __exit__(self, *exc) -> None:
        self.bar.__exit__(*exc)

    def hook(self, plan) -> Callable | None:
        """The run's progress callback, or None."""
        return kind_of(plan).progress(plan, self)

    def times(self, plan) -> Callable | None:
        """A callback ``f(t)`` following a run's simulated time: the bar (``"steps"``), a
        plain line every few seconds (``"log"``), else None."""
        if self.mode not in ("steps", "log"):
            return None
        if self.mode == "log":
            return progress_log(plan)
        task, t0 = self.tasks[plan.name], float(plan.times[0])

        def at(t):
            self.bar.update(task, completed=float(t) - t0)

        return at

    def members(self, plan) -> Callable:
        """A callback ``f(i)`` as a sweep's member ``i`` is done: the bar advances (a plain
        line every few seconds in ``"log"``)."""
        if self.mode == "log":
            return members_log(plan)
        task = self.tasks[plan.name]
        return lambda i: self.bar.advance(task)

    def start(self, plan) -> None:
        """The run begins."""
        self.bar.start_task(self.tasks[plan.name])

    def done(self, plan) -> None:
        """The run has computed: its bar full."""
        task = self.tasks[plan.name]
        total = self.bar.tasks[task].total or 1.0
        self.bar.update(task, total=total, completed=total)

    def say(self, line: str) -> None:
        """Show ``line`` (a run written) below the bars."""
        self.console.print(line, highlight=False, soft_wrap=True)


__all__ = [
    "PROGRESS_LOG_EVERY",
    "RunProgress",
    "clean",
    "compiling",
    "esc",
    "members_log",
    "progress_log",
    "say",
]
