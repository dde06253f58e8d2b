"""What ``mixdyn check`` checks of the whole file: its size before anything is built
(:func:`require_size`) and what it warns of (:func:`file_warnings`)."""

from __future__ import annotations

from ... import model as m
from ...io import schema as s
from ..kinds import kind_of


def require_size(spec: s.ModelFile, file) -> None:
    """Refuse, before building anything, a model too large to check in bounded time."""
    from ...analysis._structure import require_checkable

    require_checkable(len(spec.bodies), str(file))


def file_warnings(spec: s.ModelFile, model: m.Model, report) -> list[str]:
    """What ``mixdyn check`` warns of: no runs, redundant joint equations, bodies connected to
    nothing, forces that no run uses.

    Args:
        spec: the file's description.
        model: its model.
        report: the model's degrees of freedom at its assembled start.
    """
    out = []
    if not spec.runs:
        out.append("the file has no runs; `mixdyn run` has nothing to do")
    if report.redundant:
        out.append(
            f"redundant joint equations {', '.join(report.redundant)} are dropped by the solvers "
            "(their reactions are not unique)"
        )
    used = set()
    for j in (*model.joints, *model.drivers, *model.forces):
        used.update(j.body_indices())
    for i, b in enumerate(model.bodies):
        if i not in used:
            out.append(f"body {b.name!r} is not connected to anything")
    if model.forces and spec.runs and all(kind_of(r).motion_only for r in spec.runs):
        out.append("the forces have no effect: every run is kinematic")
    return out


__all__ = [
    "file_warnings",
    "require_size",
]
