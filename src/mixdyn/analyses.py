"""Analyses as values: what to compute and how, prepared once and run over any time grid.

Each analysis is an immutable, keyword-only object, checked when made (an unknown option is a
:class:`~mixdyn.errors.ModelError` with the close matches, a bad value names its option):

* :class:`Kinematic` — every degree of freedom driven: positions, velocities, accelerations;
* :class:`Forward` — forces known, motion sought, with its integration method
  (``Forward(method=md.Projection(rtol=1e-10))``);
* :class:`Inverse` — motion driven, driver efforts and joint reactions sought;
* :class:`Mixed` — some forces unknown, as many motions prescribed, with its mixed solver;
* :class:`Static` — the equilibrium at one time, and its stability;
* :class:`QuasiStatic` — the equilibria along a slowly driven motion.

:func:`prepare` ``(model, analysis, t0=...)`` makes the :class:`Setup` (the consistent start,
the mobility analysis, the equations, a mixed run's solvability) once; :func:`run`
``(setup, t)`` integrates it over the output times ``t``, as often as wanted::

    import mixdyn as md
    from mixdyn.analyses import Forward

    setup = md.prepare(model, Forward(method=md.Projection(rtol=1e-10)))
    coarse = md.run(setup, np.linspace(0, 1, 11))
    fine = md.run(setup, np.linspace(0, 2, 2001))   # the same start, another grid

``md.forward(model, t, method=md.Projection(rtol=1e-10))`` is the same run as ``coarse``
(bit for bit): the analysis functions make the value from their keywords, prepare it from
``t[0]`` and run it. The studies take the value:
``md.sweep(model, t, analysis=Forward(...), vary=...)``, ``md.differentiable``, ``md.fit``,
``md.optimize``.
"""

from .analysis._setup import Analysis, Setup, prepare, run
from .analysis.forward import Forward
from .analysis.inverse import Inverse
from .analysis.kinematic import Kinematic
from .analysis.mixed import Mixed
from .analysis.statics import QuasiStatic, Static

__all__ = [
    "Analysis",
    "Forward",
    "Inverse",
    "Kinematic",
    "Mixed",
    "QuasiStatic",
    "Setup",
    "Static",
    "prepare",
    "run",
]
