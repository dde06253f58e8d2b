"""How the ``mixdyn`` command ends on an error: its exit code and its one line on stderr.

A fault of the input (the file, an option, a path; a start that cannot be assembled) ends with
:data:`EXIT_INPUT` and ``FILE:LINE: element: problem; what to do``; a numerical failure
(singularity, divergence) with :data:`EXIT_NUMERICAL`, its run, time and cause; an interrupt
with 130. Any other error is a bug: :data:`EXIT_NUMERICAL` and a line asking for a report,
or, with ``MIXDYN_DEBUG=1``, its traceback.

Example::

    exit_for(FileError("no such file", file="m.yaml", hint="check the path"), "m.yaml")
    # (2, "m.yaml: no such file; check the path")
"""

from __future__ import annotations

import os

#: The command's exit codes: success, a numerical failure, bad input.
EXIT_OK, EXIT_NUMERICAL, EXIT_INPUT = 0, 1, 2
#: The exit code of an interrupt (Ctrl-C), as a shell gives it.
EXIT_INTERRUPTED = 130


def exit_for(error: BaseException, file) -> tuple[int, str] | None:
    """The exit code and the line (not yet made safe for the terminal) that ``error`` ends
    the command with.

    Args:
        error: what the command raised.
        file: the file or path the command was given (None: the command names itself),
            for errors that do not name their own.

    Returns:
        ``(code, line)``; None where ``error`` is to escape as it is: an exit of its own
        (:class:`SystemExit`), or a bug while ``MIXDYN_DEBUG`` is set.
    """
    from pydantic import ValidationError

    from ..errors import AssemblyError, MixdynError, ModelError, NumericalError
    from ..io import FileError

    where = str(file) if file is not None else "mixdyn"
    if isinstance(error, FileError):
        return EXIT_INPUT, error.one_line()
    if isinstance(error, AssemblyError):  # no start closes the joints: the description's fault
        return EXIT_INPUT, (
            f"{getattr(error, 'file', where)}: the start cannot be assembled: {error}; check "
            "the geometry, q0, initial and hold"
        )
    if isinstance(error, NumericalError):
        run = getattr(error, "run", None)
        what = f"run {run!r}: " if run else ""
        return EXIT_NUMERICAL, (
            f"{getattr(error, 'file', where)}: {what}numerical failure "
            f"({type(error).__name__}): {error}"
        )
    if isinstance(error, ModelError):
        return EXIT_INPUT, f"{where}: {error}"
    if isinstance(error, MixdynError):
        return EXIT_NUMERICAL, f"{where}: {type(error).__name__}: {error}"
    if isinstance(error, ValidationError):
        first = error.errors()[0]
        loc = ".".join(str(p) for p in first["loc"])
        return EXIT_INPUT, f"{where}: {loc}: {first['msg']}"
    if isinstance(error, KeyboardInterrupt):
        return EXIT_INTERRUPTED, f"{where}: interrupted"
    if isinstance(error, OSError):  # a file that cannot be read or written: the path's fault
        name = error.filename if error.filename is not None else where
        return EXIT_INPUT, f"{name}: {error.strerror or error}; check the path and its permissions"
    if isinstance(error, RecursionError):
        return EXIT_INPUT, f"{where}: the input is nested too deeply; simplify it"
    if not isinstance(error, Exception) or os.environ.get("MIXDYN_DEBUG"):
        return None
    return EXIT_NUMERICAL, (
        f"{where}: internal error ({type(error).__name__}: {error}); please report it "
        "(MIXDYN_DEBUG=1 shows the traceback)"
    )


__all__ = ["EXIT_INPUT", "EXIT_INTERRUPTED", "EXIT_NUMERICAL", "EXIT_OK", "exit_for"]
