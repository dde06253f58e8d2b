"""Model of a planar mechanism: bodies, joints, drivers, forces and laws of time."""

from ._body import Body, Ground
from ._cams import CamFollower
from ._contact_friction import ContactFriction
from ._contact_pairs import (
    BoxLineContact,
    CircleContact,
    CircleLineContact,
    CirclePolylineContact,
    JournalBearing,
    SliderInGuide,
)
from ._contact_sets import CircleSetContact
from ._contacts import BeltDrive, GearPair, RackPinion, RollingDisks, RollingOnLine
from ._declare import ELEMENTS, element
from ._drivers import (
    CoordinateDriver,
    DistanceDriver,
    Driver,
    PointDriver,
    RelativeAngleDriver,
)
from ._forces import (
    ForceElement,
    GeneralizedForce,
    PointForce,
    RotarySpringDamper,
    SpringDamper,
    StateFunction,
    Torque,
)
from ._friction import JointFriction
from ._joints import Distance, Joint, PinInSlot, Revolute, Translational, Weld
from ._laws import (
    Constant,
    FunctionLaw,
    Harmonic,
    Law,
    PiecewisePolynomial,
    Polynomial,
    QuinticHermite,
    Ramp,
    Spline,
    as_law,
)
from ._model import Model
from ._polygon_sets import PolygonSetContact
from ._reaction_dependent import ReactionDependent

#: The element registries that :data:`ELEMENTS` replaced, by their old names and the section
#: and file names they held.
_REPLACED = {
    "JOINT_TYPES": ("joints", ("revolute", "translational", "weld", "distance", "pin_in_slot")),
    "CONTACT_TYPES": ("joints", ("gear_pair", "rolling_disks", "rack_pinion", "rolling_on_line")),
    "CAM_TYPES": ("joints", ("cam_follower",)),
    "DRIVER_TYPES": ("drivers", ("coordinate", "point", "relative_angle", "distance")),
    "FORCE_TYPES": ("forces", ("point_force", "torque", "spring_damper", "rotary_spring_damper")),
}


def __getattr__(name: str):
    if name in _REPLACED:
        import warnings

        group, names = _REPLACED[name]
        warnings.warn(
            f"mixdyn.{name} is deprecated: use mixdyn.model.ELEMENTS[{group!r}] "
            "(every registered element class by file name)",
            DeprecationWarning,
            stacklevel=2,
        )
        registry = {n: ELEMENTS[group][n].cls for n in names}
        if name == "FORCE_TYPES":
            registry["generalized"] = GeneralizedForce
        return registry
    raise AttributeError(f"module 'mixdyn.model' has no attribute {name!r}")


__all__ = [
    "ELEMENTS",
    "BeltDrive",
    "Body",
    "BoxLineContact",
    "CamFollower",
    "CircleContact",
    "CircleLineContact",
    "CirclePolylineContact",
    "CircleSetContact",
    "Constant",
    "ContactFriction",
    "CoordinateDriver",
    "Distance",
    "DistanceDriver",
    "Driver",
    "ForceElement",
    "FunctionLaw",
    "GearPair",
    "GeneralizedForce",
    "Ground",
    "Harmonic",
    "Joint",
    "JointFriction",
    "JournalBearing",
    "Law",
    "Model",
    "PiecewisePolynomial",
    "PinInSlot",
    "PointDriver",
    "PointForce",
    "PolygonSetContact",
    "Polynomial",
    "QuinticHermite",
    "RackPinion",
    "Ramp",
    "ReactionDependent",
    "RelativeAngleDriver",
    "Revolute",
    "RollingDisks",
    "RollingOnLine",
    "RotarySpringDamper",
    "SliderInGuide",
    "Spline",
    "SpringDamper",
    "StateFunction",
    "Torque",
    "Translational",
    "Weld",
    "as_law",
    "element",
]

# Every registered element class is a name of this package (and of mixdyn) at run time; the
# import above names it for readers of the source (type checkers, the API reference).
for _group in ELEMENTS.values():
    for _kind in _group.values():
        globals().setdefault(_kind.cls.__name__, _kind.cls)
        if _kind.cls.__name__ not in __all__:
            __all__.append(_kind.cls.__name__)
del _group, _kind
