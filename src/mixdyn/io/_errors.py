"""The error of a model file: where (file, line, element) and what to do, on one line."""

from __future__ import annotations

from ..errors import ModelError


class FileError(ModelError):
    """A model file is wrong: its form, a name, a unit, an expression, a run.

    ``str(error)`` is one line: ``FILE:LINE: ELEMENT: PROBLEM; HINT``.

    Attributes:
        file: the file's path (or ``"<string>"``).
        line: 1-based line of the offending value, or None.
        element: what is wrong, e.g. ``"joint 'A', point_i"``; also ``ModelError.element``.
        problem: what is wrong with it.
        hint: what to do.
    """

    def __init__(
        self,
        problem: str,
        element: str | None = None,
        *,
        file: str | None = None,
        line: int | None = None,
        hint: str = "",
    ):
        self.file = file
        self.line = line
        self.problem = _one_line(problem)
        self.hint = _one_line(hint)
        ModelError.__init__(self, self.problem, element)
        self.args = (self.one_line(),)

    def one_line(self) -> str:
        """``FILE:LINE: ELEMENT: PROBLEM; HINT`` (parts that are unknown are left out)."""
        where = self.file or "<model>"
        if self.line is not None:
            where += f":{self.line}"
        text = f"{where}: "
        if self.element:
            text += f"{self.element}: "
        text += self.problem
        if self.hint and self.hint not in self.problem:
            text += f"; {self.hint}"
        return text

    def __str__(self) -> str:
        return self.one_line()


def _one_line(text: str) -> str:
    return " ".join(str(text).split())
