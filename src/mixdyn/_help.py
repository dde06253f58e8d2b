"""The layout of ``mixdyn --help``: each command's summary on one line.

typer's rich help keeps a docstring's line breaks in the list of commands, breaking lines
mid-sentence; :func:`one_line_summaries` gives each command its docstring's first paragraph
as one line, which the formatter wraps.
"""

from __future__ import annotations

import inspect


def one_line_summaries(app) -> None:
    """Set the summary (``short_help``) of each command of ``app`` (a :class:`typer.Typer`)
    that has none: its docstring's first paragraph as one line."""
    for info in app.registered_commands:
        if info.short_help is None and info.callback is not None and info.callback.__doc__:
            first = inspect.cleandoc(info.callback.__doc__).split("\n\n")[0]
            info.short_help = " ".join(first.split())


__all__ = ["one_line_summaries"]
