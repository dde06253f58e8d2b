"""The errors mixdyn raises. Each one says what is wrong, where, and what to do.

Every error derives from :class:`MixdynError`. Errors about the *description* of a
mechanism (unknown names, bad values) derive from :class:`ModelError`; errors found
while *solving* (divergence, singularity) derive from :class:`NumericalError` and carry
the time at which they occurred and the elements involved.
"""

from __future__ import annotations


class MixdynError(Exception):
    """Base class of every error raised by mixdyn."""


class ModelError(MixdynError, ValueError):
    """The mechanism or analysis is described wrongly (a name, a value, a count).

    Attributes:
        element: name of the offending element (body, joint, driver, force, run), if any.
        field: the element's field at fault (``"length"``), if the fault is in one field:
            a model file reports it at that field's line.
    """

    def __init__(self, message: str, element: str | None = None, *, field: str | None = None):
        self.element = element
        self.message = message
        self.field = field
        super().__init__(f"{element}: {message}" if element else message)

    def __reduce__(self):  # pickled whole (a sweep's member errors cross processes)
        notes = list(getattr(self, "__notes__", []))
        state = {"__notes__": notes, "field": self.field}
        return type(self), (self.message, self.element), state


class DegreesOfFreedomError(ModelError):
    """The number of drivers (prescribed motions) does not match the degrees of freedom."""


class RedundantConstraintError(ModelError):
    """Constraint equations are redundant or contradict each other."""


class SolvabilityError(ModelError):
    """A mixed-dynamics problem is not solvable as posed (pairing of forces and motions)."""


class NumericalError(MixdynError, RuntimeError):
    """A solver failed on a well-formed problem.

    Attributes:
        time: simulation time [model time unit] at which it failed, or None.
        elements: names of the constraint equations or elements involved.
    """

    def __init__(self, message: str, time: float | None = None, elements=()):
        self.time = time
        self.elements = tuple(elements)
        self.message = message
        where = f"at t = {time:.6g}: " if time is not None else ""
        involved = f" (involved: {', '.join(self.elements)})" if self.elements else ""
        super().__init__(f"{where}{message}{involved}")

    def __reduce__(self):  # pickled whole (a sweep's member errors cross processes)
        notes = list(getattr(self, "__notes__", []))
        return type(self), (self.message, self.time, self.elements), {"__notes__": notes}


class AssemblyError(NumericalError):
    """The constraints could not be closed from the given starting pose."""


class ConvergenceError(NumericalError):
    """A Newton iteration diverged or did not converge in its iteration limit."""


class SingularityError(NumericalError):
    """A Jacobian lost rank: a singular (dead-point, bifurcation) configuration."""


class StepSizeError(NumericalError):
    """An adaptive integrator's step size collapsed below its minimum."""


class EnergyBalanceError(NumericalError):
    """A dynamic run broke its energy balance ``T + V - E0 - W_applied - W_constraints = 0``
    beyond its tolerance: the motion jumped to another branch at a singular position, or the
    steps were too large for the accuracy the result claims."""


class ContactLostError(NumericalError):
    """A one-sided contact (a cam and its follower, a rolling disk) would have to pull: the
    bodies separate there, which the run's equations do not follow."""


class ImpactAccumulationError(NumericalError):
    """Rigid impacts accumulate without coming to rest: more impacts in one run than the
    run takes (:data:`mixdyn.analysis._impacts.MAX_IMPACTS`), none slowing to the rest
    speed at which a contact point is held at rest (chattering contacts)."""


class NonFiniteError(NumericalError):
    """A result column holds a NaN or an infinity (a singular force law, an overflow)."""
