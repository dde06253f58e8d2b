"""The runs of a model file: planned, checked, set up, executed and written.

A file's runs are found by their ``kind:`` in one registry (:mod:`.kinds`), each kind
registered by its module: :mod:`.analyses` (kinematic, statics, inverse, forward, mixed),
:mod:`.sweep`, :mod:`.identify`, :mod:`.optimize` and :mod:`.synthesis`. A :class:`Runner`
holds a file's plans and does its jobs through one module each:

* :mod:`.plan`: a run checked into a :class:`Plan` (output times, order, what a study may
  change);
* :mod:`.checks`: every check made before anything is computed (settings, columns, masses,
  mobility, a mixed run's solvability);
* :mod:`.setup`: a run's model, start and analysis keywords, made once and shared by its check
  and its run;
* :mod:`.execute`: the runs in the order of their dependencies;
* :mod:`.outputs` and :mod:`.console`: what ``mixdyn run`` writes and shows;
* the jobs of the ``mixdyn`` commands, a module each: :mod:`.report` (``check``),
  :mod:`.job` (``run``), :mod:`.pictures` (``show``, ``plot``, ``animate``), :mod:`.texts`
  (``dump``, ``schema``) and :mod:`.exits` (an error's exit code and one line);
* :mod:`.files`: a file from Python, :func:`load` and :func:`run_file` (``mixdyn.load``,
  ``mixdyn.run_file``).

Example::

    import mixdyn.io as mio
    from mixdyn.runs import Runner
    spec = mio.read("examples/antonya.yaml")
    results = Runner(spec).execute()     # every run, by name
"""

from . import analyses, identify, optimize, sweep, synthesis  # noqa: F401  (they register their kinds)
from .files import LoadedFile, load, run_file
from .kinds import KINDS, RunKind, kind_of
from .plan import Plan
from .runner import Runner, execute

__all__ = [
    "KINDS",
    "LoadedFile",
    "Plan",
    "RunKind",
    "Runner",
    "execute",
    "kind_of",
    "load",
    "run_file",
]
