"""Model of a planar mechanism: bodies, joints, drivers, forces and laws of time."""

from ._body import Body, Ground
from ._cams import CAM_TYPES, CamFollower
from ._contacts import CONTACT_TYPES, GearPair, RackPinion, RollingDisks, RollingOnLine
from ._drivers import (
    DRIVER_TYPES,
    CoordinateDriver,
    DistanceDriver,
    Driver,
    PointDriver,
    RelativeAngleDriver,
)
from ._forces import (
    FORCE_TYPES,
    ForceElement,
    GeneralizedForce,
    PointForce,
    RotarySpringDamper,
    SpringDamper,
    StateFunction,
    Torque,
)
from ._friction import JointFriction
from ._joints import JOINT_TYPES, Distance, Joint, PinInSlot, Revolute, Translational, Weld
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

__all__ = [
    "CAM_TYPES",
    "CONTACT_TYPES",
    "DRIVER_TYPES",
    "FORCE_TYPES",
    "JOINT_TYPES",
    "Body",
    "CamFollower",
    "Constant",
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
    "Law",
    "Model",
    "PiecewisePolynomial",
    "PinInSlot",
    "PointDriver",
    "PointForce",
    "Polynomial",
    "QuinticHermite",
    "RackPinion",
    "Ramp",
    "RelativeAngleDriver",
    "Revolute",
    "RollingDisks",
    "RollingOnLine",
    "RotarySpringDamper",
    "Spline",
    "SpringDamper",
    "StateFunction",
    "Torque",
    "Translational",
    "Weld",
    "as_law",
]
