"""``mixdyn check``'s report of a model file: the model, its assembled start, its degrees of
freedom (none of these for a file of synthesis runs alone, which has no mechanism), each run
checked and described by its kind, the warnings and, asked for, every number as understood
(:func:`mixdyn.io.explain.lines`).

Example::

    for line in report("examples/antonya.yaml"):
        print(line)          # rich markup, the file's names escaped
"""

from __future__ import annotations

from collections.abc import Iterator

from .._hints import count
from .console import esc


def report(file, explain: bool = False) -> Iterator[str]:
    """The lines of ``mixdyn check FILE``, each as soon as it is known (rich markup), the
    last ``ok``.

    Args:
        file: the model file.
        explain: also every number as understood: where it is, as written, in the model's
            units and in SI.

    Raises:
        FileError: the file or a run is wrong (after the lines known before).
        AssemblyError: no start closes the joints.
    """
    from .. import analysis as an
    from ..io import read
    from .checks import file_warnings, require_size
    from .kinds import kind_of
    from .runner import Runner
    from .setup import start_q

    spec = read(file)
    require_size(spec, file)
    runner = Runner(spec)
    model = runner.model
    if model is None:  # a file of synthesis runs alone: no mechanism to assemble
        yield f"[bold]{esc(file)}[/bold]: no mechanism (its runs make their own)"
        for plan in runner.order():
            yield kind_of(plan).describe(plan, None, None)
        for w in runner.b.readings.warnings:
            yield f"[yellow]warning[/yellow]: {esc(w)}"
        yield from _explained(runner, explain)
        yield "[green]ok[/green]"
        return
    asm = an.assemble(model, start_q(model), hold=spec.assembly.hold)
    dofs = an.degrees_of_freedom(model, asm.q)
    yield f"[bold]{esc(file)}[/bold]: {esc(model.summary())}"
    yield f"assembled start: residual {asm.residual:.2e} in {count(asm.iterations, 'iteration')}"
    yield f"degrees of freedom: {dofs.dof}"
    yield f"redundant joint equations: {', '.join(dofs.redundant) or 'none'}"
    redundant = ", ".join(dofs.redundant_drivers)
    yield f"model drivers: {dofs.n_drivers}" + (f" (redundant: {redundant})" if redundant else "")
    warnings = [*runner.b.readings.warnings, *file_warnings(spec, model, dofs)]
    for plan in runner.order():
        runner.check_masses(plan)
        mobility = runner.mobility(plan)
        runner.check_solvable(plan)
        yield kind_of(plan).describe(plan, mobility, model)
    for w in warnings:
        yield f"[yellow]warning[/yellow]: {esc(w)}"
    yield from _explained(runner, explain)
    yield "[green]ok[/green]"


def _explained(runner, explain: bool) -> Iterator[str]:
    """With ``explain``, every number as understood (:func:`mixdyn.io.explain.lines`)."""
    if explain:
        from ..io.explain import lines

        for line in lines(runner.b):
            yield esc(line)


__all__ = ["report"]
