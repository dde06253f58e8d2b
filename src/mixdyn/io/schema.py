"""The model-file schema: a validated description of a mechanism and its analyses.

A model file (YAML) is read into a :class:`ModelFile`, a tree of pydantic models that checks the
*form* of the description: required fields, types, allowed keys, the kinds of joints, drivers,
forces and runs. The *meaning* (names that exist, units of the right dimension, expressions
that parse) is checked when the description is built into a :class:`mixdyn.Model`
(:mod:`mixdyn.io.load`), where the model's unit system is known.

Scalars (:data:`Scalar`) are numbers in the model's units, or strings with units
(``"500 N*mm"``, ``"30 deg"``) or constant expressions (``"pi/6"``). Laws of time
(:data:`LawSpec`) are numbers, expression strings (``"10*sin(pi*t/2)"``) or one-key mappings
(``{polynomial: [0, 2]}``, ``{harmonic: {amplitude: 1, omega: 2}}``, ...).

``mixdyn schema`` writes :func:`json_schema` for editors and validators.
"""

from __future__ import annotations

import math
import re
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    model_validator,
)

FORMAT_VERSION = 1

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_\-]*$")


def _name(v: str) -> str:
    if not _NAME.match(v) or len(v) > 64:
        raise ValueError(
            f"{v!r} is not a valid name: use letters, digits, '_' and '-', starting with a "
            "letter or '_' (at most 64 characters)"
        )
    return v


def _scalar(v: Any) -> Any:
    if isinstance(v, bool) or not isinstance(v, int | float | str):
        raise ValueError(f"expected a number or a string with units (e.g. '500 N*mm'), got {v!r}")
    if isinstance(v, float) and not math.isfinite(v):
        raise ValueError(f"{v!r} is not a finite number")
    if isinstance(v, str) and not v.strip():
        raise ValueError("empty value; write a number or a number with units")
    return v


def _ref(v: str) -> str:
    if not v or any(not _NAME.match(p) for p in v.split(".")) or len(v) > 200:
        raise ValueError(f"{v!r} is not a reference; write 'body' or 'body.point'")
    return v


def _relative_file(v: str) -> str:
    p = v.replace("\\", "/")
    if not p or p.startswith("/") or ".." in p.split("/") or ":" in p:
        raise ValueError(
            f"{v!r} must be a relative file name inside the run's output folder (no '..')"
        )
    return v


#: File types of figures and animations (those of :mod:`mixdyn.viz`).
PLOT_SUFFIXES = (".png", ".svg", ".pdf")
ANIMATION_SUFFIXES = (".gif", ".mp4", ".html")


def _suffixed(suffixes: tuple[str, ...], what: str):
    def check(v: str) -> str:
        if not v.lower().endswith(suffixes) or v.rsplit("/", 1)[-1].startswith("."):
            raise ValueError(f"cannot write {_article(what)} to {v!r}: use {', '.join(suffixes)}")
        return v

    return check


def _article(what: str) -> str:
    return ("an " if what[0] in "aeiou" else "a ") + what


_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")


def _text(v: str) -> str:
    """One line of plain text: no control characters (no terminal escapes)."""
    if _CONTROL.search(v):
        raise ValueError("contains a control character; write plain text on one line")
    return v


def _paragraph(v: str) -> str:
    """Plain text that may span lines: no control characters other than newlines and tabs."""
    return _text(v.replace("\n", " ").replace("\t", " ").replace("\r", " "))


Name = Annotated[str, AfterValidator(_name)]
"""A name: letters, digits, ``_`` and ``-``, starting with a letter or ``_``."""

Scalar = Annotated[float | str, BeforeValidator(_scalar)]
"""A number in model units, or a string: a number or constant expression with a unit."""

Ref = Annotated[str, AfterValidator(_ref)]
"""A reference: ``"body"``, ``"body.point"``, ``"body.x"`` (coordinates), ``"ground.A"``."""

Vec2 = tuple[Scalar, Scalar]
"""Two scalars ``[x, y]``."""

RelativeFile = Annotated[str, AfterValidator(_relative_file)]
PlotFile = Annotated[RelativeFile, AfterValidator(_suffixed(PLOT_SUFFIXES, "plot"))]
AnimationFile = Annotated[RelativeFile, AfterValidator(_suffixed(ANIMATION_SUFFIXES, "animation"))]
Text = Annotated[str, AfterValidator(_text)]
"""One line of plain text (a title, a label, the model's name)."""


class Spec(BaseModel):
    """Base of every part of the description: unknown keys are errors; values immutable."""

    model_config = ConfigDict(extra="forbid", frozen=True)


# --------------------------------------------------------------------------- laws
class ExpressionSpec(Spec):
    """``{expr: "10*sin(pi*t/2)", unit: N}``: an expression of ``t`` [model time unit]; its
    value is in ``unit`` (default: the model's unit of what it drives)."""

    expr: str
    unit: str | None = None


class ConstantSpec(Spec):
    """``{constant: 5}``."""

    constant: Scalar


class PolynomialSpec(Spec):
    """``{polynomial: [c0, c1, ...]}``: ``sum c_k t**k``, coefficients in ``unit`` per time**k
    (default: model units)."""

    polynomial: list[Scalar] = Field(min_length=1)
    unit: str | None = None


class RampArgs(Spec):
    start: Scalar = 0.0
    rate: Scalar


class RampSpec(Spec):
    """``{ramp: {start: 0, rate: "2 rad/s"}}``: ``start + rate t``."""

    ramp: RampArgs


class HarmonicArgs(Spec):
    amplitude: Scalar
    omega: Scalar
    phase: Scalar = 0.0
    offset: Scalar = 0.0


class HarmonicSpec(Spec):
    """``{harmonic: {amplitude, omega, phase, offset}}``: ``offset + amplitude sin(omega t +
    phase)``."""

    harmonic: HarmonicArgs


class SplineArgs(Spec):
    t: list[Scalar] = Field(min_length=2)
    y: list[Scalar] = Field(min_length=2)
    kind: Literal["cubic", "quintic"] = "cubic"
    unit: str | None = None


class SplineSpec(Spec):
    """``{spline: {t: [...], y: [...], kind: cubic}}``: an interpolating spline."""

    spline: SplineArgs


class HermiteArgs(Spec):
    t: list[Scalar] = Field(min_length=2)
    y: list[Scalar] = Field(min_length=2)
    yd: list[Scalar] = Field(min_length=2)
    ydd: list[Scalar] = Field(min_length=2)
    unit: str | None = None


class HermiteSpec(Spec):
    """``{hermite: {t, y, yd, ydd}}``: quintic Hermite through values and two derivatives."""

    hermite: HermiteArgs


class PiecewiseArgs(Spec):
    breaks: list[float] = Field(min_length=2)
    coeffs: list[list[float]] = Field(min_length=1)


class PiecewiseSpec(Spec):
    """``{piecewise: {breaks, coeffs}}``: a piecewise polynomial (scipy ``PPoly`` layout:
    ``coeffs[k][i]`` of ``(t - breaks[i])**(K-k)``), in model units."""

    piecewise: PiecewiseArgs


LAW_KEYS = ("expr", "constant", "polynomial", "ramp", "harmonic", "spline", "hermite", "piecewise")


def _law_tag(v: Any) -> str | None:
    if isinstance(v, Spec):
        for k in LAW_KEYS:
            if k in type(v).model_fields:
                return k
        return None
    if isinstance(v, dict):
        keys = [k for k in LAW_KEYS if k in v]
        return keys[0] if len(keys) == 1 else None
    if isinstance(v, int | float | str) and not isinstance(v, bool):
        return "scalar"
    return None


LawSpec = Annotated[
    Annotated[Scalar, Tag("scalar")]
    | Annotated[ExpressionSpec, Tag("expr")]
    | Annotated[ConstantSpec, Tag("constant")]
    | Annotated[PolynomialSpec, Tag("polynomial")]
    | Annotated[RampSpec, Tag("ramp")]
    | Annotated[HarmonicSpec, Tag("harmonic")]
    | Annotated[SplineSpec, Tag("spline")]
    | Annotated[HermiteSpec, Tag("hermite")]
    | Annotated[PiecewiseSpec, Tag("piecewise")],
    Discriminator(
        _law_tag,
        custom_error_type="law",
        custom_error_message=(
            "a law is a number, an expression such as '2*t', or a mapping with exactly one of "
            "the keys " + ", ".join(LAW_KEYS)
        ),
    ),
]
"""A law of time (or, for force magnitudes, of the state)."""


# --------------------------------------------------------------------------- model parts
class UnitsSpec(Spec):
    """The model's unit system (pint spellings); angles are always radians."""

    length: str = "m"
    mass: str = "kg"
    time: str = "s"


class GroundSpec(Spec):
    """The fixed frame: named points in global coordinates [length]."""

    points: dict[str, Vec2] = Field(default_factory=dict)


class BodySpec(Spec):
    """A rigid body; its frame is at the centre of mass.

    ``q0`` is the rough starting pose ``[x, y, phi]``; ``points`` and ``vectors`` are given in
    the body frame.
    """

    name: Name
    mass: Scalar = 0.0
    inertia: Scalar = 0.0
    q0: tuple[Scalar, Scalar, Scalar] = (0.0, 0.0, 0.0)
    points: dict[str, Vec2] = Field(default_factory=dict)
    vectors: dict[str, Vec2] = Field(default_factory=dict)


class RevoluteSpec(Spec):
    type: Literal["revolute"]
    name: Name
    point_i: Ref
    point_j: Ref


class WeldSpec(Spec):
    type: Literal["weld"]
    name: Name
    point_i: Ref
    point_j: Ref
    angle: Scalar = 0.0


class TranslationalSpec(Spec):
    type: Literal["translational"]
    name: Name
    point_i: Ref
    point_j: Ref
    axis: Vec2 | Name = (1.0, 0.0)
    angle: Scalar = 0.0


class PinInSlotSpec(Spec):
    type: Literal["pin_in_slot"]
    name: Name
    point_i: Ref
    point_j: Ref
    axis: Vec2 | Name = (1.0, 0.0)


class DistanceSpec(Spec):
    type: Literal["distance"]
    name: Name
    point_i: Ref
    point_j: Ref
    length: Scalar


JointSpec = Annotated[
    RevoluteSpec | WeldSpec | TranslationalSpec | PinInSlotSpec | DistanceSpec,
    Field(discriminator="type"),
]


class CoordinateDriverSpec(Spec):
    """Prescribes a body coordinate, ``coordinate: crank.phi``."""

    type: Literal["coordinate"]
    name: Name
    coordinate: Ref
    law: LawSpec


class PointDriverSpec(Spec):
    type: Literal["point"]
    name: Name
    point: Ref
    coordinate: Literal["x", "y"]
    law: LawSpec


class RelativeAngleDriverSpec(Spec):
    type: Literal["relative_angle"]
    name: Name
    body_i: Name
    body_j: Name
    law: LawSpec


class DistanceDriverSpec(Spec):
    type: Literal["distance"]
    name: Name
    point_i: Ref
    point_j: Ref
    law: LawSpec


DriverSpec = Annotated[
    CoordinateDriverSpec | PointDriverSpec | RelativeAngleDriverSpec | DistanceDriverSpec,
    Field(discriminator="type"),
]


class PointForceSpec(Spec):
    type: Literal["point_force"]
    name: Name
    point: Ref
    along: Vec2 = (1.0, 0.0)
    frame: Literal["ground", "body"] = "ground"
    law: LawSpec = 0.0


class TorqueSpec(Spec):
    type: Literal["torque"]
    name: Name
    body: Name
    law: LawSpec = 0.0
    reaction: Name | None = None


class SpringDamperSpec(Spec):
    type: Literal["spring_damper"]
    name: Name
    point_i: Ref
    point_j: Ref
    stiffness: Scalar = 0.0
    damping: Scalar = 0.0
    free_length: Scalar = 0.0
    actuator: LawSpec = 0.0


class RotarySpringDamperSpec(Spec):
    type: Literal["rotary_spring_damper"]
    name: Name
    body_i: Name
    body_j: Name
    stiffness: Scalar = 0.0
    damping: Scalar = 0.0
    free_angle: Scalar = 0.0
    actuator: LawSpec = 0.0


ForceSpec = Annotated[
    PointForceSpec | TorqueSpec | SpringDamperSpec | RotarySpringDamperSpec,
    Field(discriminator="type"),
]


class AssemblySpec(Spec):
    """How the starting pose is closed: coordinates held at their ``q0`` value."""

    hold: list[Ref] = Field(default_factory=list)


# --------------------------------------------------------------------------- runs
class TimeSpec(Spec):
    """Output times: ``span`` with ``n`` points or a ``step``, or explicit ``values``."""

    span: tuple[Scalar, Scalar] | None = None
    n: int | None = Field(default=None, ge=2, le=1_000_000)
    step: Scalar | None = None
    values: list[Scalar] | None = Field(default=None, min_length=1)

    @model_validator(mode="after")
    def _one_form(self):
        explicit = self.values is not None and (self.span, self.n, self.step) == (None,) * 3
        spanned = self.values is None and self.span is not None
        ok = explicit or (spanned and (self.n is None) != (self.step is None))
        if not ok:
            raise ValueError("give 'span' with either 'n' or 'step', or give 'values' alone")
        return self


class PrescribedSpec(Spec):
    """A prescribed motion: ``coordinate`` (``slider.x``; ``slider.D.x`` for a point) follows
    ``law`` or the motion computed by the run ``from_run``."""

    coordinate: Ref
    name: Name | None = None
    law: LawSpec | None = None
    from_run: Name | None = None

    @model_validator(mode="after")
    def _one_source(self):
        if (self.law is None) == (self.from_run is None):
            raise ValueError("give exactly one of 'law' and 'from_run'")
        return self


class ReferenceSpec(Spec):
    """A reference curve drawn beside the plotted columns: an expression of ``t``."""

    expr: str
    label: Text | None = None
    unit: str | None = None


class PlotSpec(Spec):
    """A figure of some columns against time, written to the run's output folder."""

    file: PlotFile
    columns: list[str] = Field(min_length=1)
    title: Text | None = None
    ylabel: Text | None = None
    reference: ReferenceSpec | None = None


class AnimationSpec(Spec):
    """An animation of the run, written to the run's output folder."""

    file: AnimationFile = "animation.gif"
    html: bool = True
    fps: int = Field(default=20, ge=1, le=120)
    frames: int = Field(default=80, ge=2, le=2000)
    trace: list[Ref] = Field(default_factory=list)


class _RunSpec(Spec):
    name: Name
    time: TimeSpec
    linear_solver: Literal["auto", "dense", "sparse"] = "auto"
    drivers: list[Name] | None = None
    prescribed: list[PrescribedSpec] = Field(default_factory=list)
    hold: list[Ref] | None = None
    initial: dict[str, Scalar] = Field(default_factory=dict)
    velocities: dict[str, Scalar] = Field(default_factory=dict)
    plots: list[PlotSpec] = Field(default_factory=list)
    animation: AnimationSpec | None = None


class KinematicRunSpec(_RunSpec):
    """Motion prescribed for every degree of freedom (``mixdyn.kinematic``)."""

    kind: Literal["kinematic"]
    tol: float | None = Field(default=None, gt=0, allow_inf_nan=False)
    max_iter: int = Field(default=25, ge=1, le=1000)


Method = Literal["projection", "baumgarte", "partitioning", "generalized-alpha"]
Option = float | int | str | bool | None  # None: a check turned off (energy_tol: null)


class ForwardRunSpec(_RunSpec):
    """Forces known, motion sought (``mixdyn.forward``)."""

    kind: Literal["forward"]
    method: Method = "projection"
    rtol: float = Field(default=1e-8, gt=0, allow_inf_nan=False)
    atol: float = Field(default=1e-10, gt=0, allow_inf_nan=False)
    dt: Scalar | None = None
    options: dict[str, Option] = Field(default_factory=dict)


class InverseRunSpec(_RunSpec):
    """Motion prescribed, driving forces and reactions sought (``mixdyn.inverse``)."""

    kind: Literal["inverse"]
    options: dict[str, Option] = Field(default_factory=dict)


class MixedRunSpec(_RunSpec):
    """Some forces unknown, as many motions prescribed (``mixdyn.mixed``)."""

    kind: Literal["mixed"]
    unknown: list[Name] = Field(min_length=1)
    solver: Literal["augmented", "partition"] = "augmented"
    independent: list[Ref] | None = None
    method: Method = "projection"
    rtol: float = Field(default=1e-8, gt=0, allow_inf_nan=False)
    atol: float = Field(default=1e-10, gt=0, allow_inf_nan=False)
    dt: Scalar | None = None
    options: dict[str, Option] = Field(default_factory=dict)


RunSpec = Annotated[
    KinematicRunSpec | ForwardRunSpec | InverseRunSpec | MixedRunSpec,
    Field(discriminator="kind"),
]


class ModelFile(Spec):
    """A model file: a mechanism in one unit system, and named runs of analyses on it."""

    mixdyn: Literal[1] = FORMAT_VERSION
    name: Text = "mechanism"
    description: Annotated[str, AfterValidator(_paragraph)] | None = None
    units: UnitsSpec = UnitsSpec()
    gravity: Vec2 = (0.0, 0.0)
    parameters: dict[str, Scalar] = Field(default_factory=dict)
    ground: GroundSpec = GroundSpec()
    bodies: list[BodySpec] = Field(min_length=1)
    joints: list[JointSpec] = Field(default_factory=list)
    drivers: list[DriverSpec] = Field(default_factory=list)
    forces: list[ForceSpec] = Field(default_factory=list)
    assembly: AssemblySpec = AssemblySpec()
    runs: list[RunSpec] = Field(default_factory=list)

    def __eq__(self, other) -> bool:
        # Equal descriptions, whatever file (and lines) they were read from.
        if not isinstance(other, ModelFile):
            return NotImplemented
        return self.model_dump() == other.model_dump()

    __hash__ = None  # type: ignore[assignment]

    def run(self, name: str):
        """The run called ``name``."""
        for r in self.runs:
            if r.name == name:
                return r
        known = ", ".join(r.name for r in self.runs) or "(none)"
        raise KeyError(f"no run {name!r}; runs: {known}")


def json_schema() -> dict:
    """The JSON Schema of a model file (draft 2020-12)."""
    schema = ModelFile.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema.setdefault("title", "mixdyn model file")
    return schema
