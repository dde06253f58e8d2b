"""The runs of a model file: planned, checked, set up and executed.

Example::

    import mixdyn.io as mio
    from mixdyn.runs import Runner
    spec = mio.read("examples/antonya.yaml")
    results = Runner(spec).execute()     # every run, by name
"""

from . import identify, optimize, sweep  # noqa: F401  (they register their run kinds)
from .plan import Plan
from .runner import Runner, execute

__all__ = ["Plan", "Runner", "execute"]
