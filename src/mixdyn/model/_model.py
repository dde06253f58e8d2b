"""The immutable model of a planar mechanism."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._arrays import as_f64
from ..errors import ModelError
from ..units import SI, UnitSystem
from ._body import GROUND_NAME, Body, Ground
from ._clearance import clearance_contacts
from ._drivers import Driver
from ._element import Resolver
from ._forces import ForceElement
from ._joints import Joint

COORDINATES = ("x", "y", "phi")


def _traced(leaves) -> bool:
    """Whether any of ``leaves`` is being traced (inside ``jit``, ``grad``, ``vmap``)."""
    return any(isinstance(x, jax.core.Tracer) for x in leaves)


def _unique(items, what):
    seen = set()
    for it in items:
        if it.name in seen:
            raise ModelError(f"duplicate {what} name; every name must be unique", it.name)
        seen.add(it.name)


def _bind_force(force: ForceElement, r: Resolver, joints) -> ForceElement:
    """``force`` bound to the bodies of ``r`` and, where it acts in a joint, to ``joints``."""
    bound = force.bind(r)
    return bound.with_joint(joints) if hasattr(force, "with_joint") else bound


class Model(eqx.Module):
    """A planar mechanism: bodies, joints, drivers and forces, in one unit system.

    The model is an immutable PyTree: numbers are array leaves, names and topology are static.
    Equal structures share compiled code; changing a number (a mass, a length) never recompiles.

    Args:
        bodies: the moving bodies. Body ``b`` owns coordinates ``q[3b:3b+3] = [x, y, phi]``.
        joints: joints (constraints ``Phi^K(q) = 0``).
        drivers: prescribed motions ``Phi^D(q, t) = 0`` used by kinematic and inverse analyses
            (and, as motion constraints with reported efforts, by forward dynamics).
        forces: force elements (``Q^A``).
        ground: the fixed frame and its points [length].
        gravity: (2,) acceleration of gravity [length/time**2], e.g. ``(0, -9.81)`` in SI.
        units: the model's unit system; every number is in it.
        name: a name for messages and files.
    """

    bodies: tuple[Body, ...]
    joints: tuple[Joint, ...]
    drivers: tuple[Driver, ...]
    forces: tuple[ForceElement, ...]
    ground: Ground
    gravity: jax.Array
    units: UnitSystem = eqx.field(static=True)
    name: str = eqx.field(static=True)

    def __init__(
        self,
        bodies,
        joints=(),
        drivers=(),
        forces=(),
        ground=None,
        gravity=(0.0, 0.0),
        units: UnitSystem = SI,
        name: str = "mechanism",
    ):
        bodies = tuple(bodies)
        if not bodies:
            raise ModelError("a model needs at least one moving body", name)
        for b in bodies:
            if not isinstance(b, Body):
                raise ModelError(f"expected a Body, got {type(b).__name__}", name)
        _unique(bodies, "body")
        joints, bearings = clearance_contacts(joints)
        forces = (*forces, *bearings)
        elements = [*joints, *drivers, *forces]
        _unique(elements, "element")
        for kind, items, base in (
            ("joint", joints, Joint),
            ("driver", drivers, Driver),
            ("force", forces, ForceElement),
        ):
            for it in items:
                if not isinstance(it, base):
                    raise ModelError(
                        f"expected a {kind}, got {type(it).__name__}", getattr(it, "name", None)
                    )
        ground = ground if ground is not None else Ground()
        if isinstance(ground, dict):
            ground = Ground(ground)
        r = Resolver(ground, bodies)
        self.bodies = bodies
        self.joints = tuple(j.bind(r) for j in joints)
        self.drivers = tuple(d.bind(r) for d in drivers)
        bound = tuple(_bind_force(f, r, self.joints) for f in forces)
        # an element acting at another force element (a contact's friction) checked against it
        self.forces = tuple(
            f.with_forces(bound, 3 * len(self.bodies)) if hasattr(f, "with_forces") else f
            for f in bound
        )
        self.ground = ground
        try:
            g = np.asarray(gravity, dtype=float)
        except (TypeError, ValueError):
            g = np.full(1, np.nan)
        if g.shape != (2,) or not np.all(np.isfinite(g)):
            raise ModelError(f"gravity must be two finite numbers (gx, gy), got {gravity!r}", name)
        self.gravity = as_f64(g)
        if not isinstance(units, UnitSystem):
            raise ModelError("units must be a mixdyn.UnitSystem", name)
        self.units = units
        self.name = name

    # ----------------------------------------------------------------- sizes and names
    @property
    def nb(self) -> int:
        """Number of moving bodies."""
        return len(self.bodies)

    @property
    def nq(self) -> int:
        """Number of coordinates, ``3 nb``."""
        return 3 * len(self.bodies)

    @property
    def body_names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.bodies)

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        """``("crank.x", "crank.y", "crank.phi", ...)``, one per entry of ``q``."""
        return tuple(f"{b.name}.{c}" for b in self.bodies for c in COORDINATES)

    def coordinate_index(self, ref: str) -> int:
        """Index in ``q`` of ``"body.x"``, ``"body.y"`` or ``"body.phi"``."""
        names = self.coordinate_names
        if ref not in names:
            raise ModelError(
                f"unknown coordinate {ref!r}; use 'body.x', 'body.y' or 'body.phi' "
                f"with a body of {', '.join(self.body_names)}"
            )
        return names.index(ref)

    def body_index(self, name: str) -> int:
        if name not in self.body_names:
            raise ModelError(f"unknown body; known: {', '.join(self.body_names)}", name)
        return self.body_names.index(name)

    def element(self, name: str):
        """The joint, driver or force called ``name``."""
        for e in (*self.joints, *self.drivers, *self.forces):
            if e.name == name:
                return e
        known = [e.name for e in (*self.joints, *self.drivers, *self.forces)]
        raise ModelError(f"no such element; known: {', '.join(known) or '(none)'}", name)

    @property
    def q0(self) -> jax.Array:
        """The bodies' rough initial coordinates, stacked, (3 nb,) [length, length, rad].

        Stacked with NumPy (a JAX concatenation of every body compiles in a time growing
        quadratically with their number), with JAX only inside a trace."""
        parts = [b.q0 for b in self.bodies]
        if _traced(parts):
            return jnp.concatenate(parts)
        return jnp.asarray(np.concatenate([np.asarray(x) for x in parts]))

    @property
    def mass_diagonal(self) -> jax.Array:
        """Diagonal of ``M = diag(m_i, m_i, J_i)``, (3 nb,) [mass, mass, mass*length**2]
        (NumPy-built outside a trace, as :attr:`q0`)."""
        m = [b.mass for b in self.bodies]
        inertia = [b.inertia for b in self.bodies]
        if _traced(m) or _traced(inertia):
            return jnp.concatenate([jnp.stack([b.mass, b.mass, b.inertia]) for b in self.bodies])
        m = np.asarray([np.asarray(x) for x in m])
        inertia = np.asarray([np.asarray(x) for x in inertia])
        return as_f64(np.stack([m, m, inertia], axis=1).reshape(-1))

    @property
    def n_joint_equations(self) -> int:
        return sum(j.n_equations for j in self.joints)

    def replace(self, **changes) -> Model:
        """A new model with some constructor arguments changed (elements re-bound)."""
        args = dict(
            bodies=self.bodies,
            joints=self.joints,
            drivers=self.drivers,
            forces=self.forces,
            ground=self.ground,
            gravity=self.gravity,
            units=self.units,
            name=self.name,
        )
        args.update(changes)
        return Model(**args)

    def bind_force(self, force: ForceElement) -> ForceElement:
        """``force`` bound to this model's bodies, points and joints, as the constructor
        binds its forces (a model file's sweep builds one force a member again)."""
        return _bind_force(force, Resolver(self.ground, self.bodies), self.joints)

    def point_position(self, q, ref) -> jax.Array:
        """Global position (2,) [length] of a point reference (``"body.point"``) at ``q``."""
        from ._geometry import point

        b, s = Resolver(self.ground, self.bodies).point(ref, "point")
        return point(jnp.asarray(q), b, s)

    def summary(self) -> str:
        """A short human-readable description."""
        from .._hints import count

        return (
            f"{self.name}: {count(self.nb, 'body', 'bodies')} ({count(self.nq, 'coordinate')}), "
            f"{count(len(self.joints), 'joint')} ({count(self.n_joint_equations, 'equation')}), "
            f"{count(len(self.drivers), 'driver')}, {count(len(self.forces), 'force')}; "
            f"units {self.units.describe()}"
        )

    # ----------------------------------------------------------------- display
    def _rows(self) -> tuple[list[tuple], list[tuple]]:
        """``(bodies, elements)``: per body ``(name, mass, inertia, q0, points)`` and per
        element ``(group, name, type, bodies, numbers)``, as text in the model's units."""
        u = self.units
        bodies = []
        for b in self.bodies:
            pts = ", ".join(f"{k} {_vec(v)}" for k, v in b.points.items()) or "(the origin only)"
            bodies.append(
                (
                    b.name,
                    f"{_num(b.mass)} {u.label('mass')}",
                    f"{_num(b.inertia)} {u.label('inertia')}",
                    _vec(b.q0),
                    pts,
                )
            )
        names = ["ground", *(b.name for b in self.bodies)]

        def between(e) -> str:
            if isinstance(getattr(e, "bi", None), int) and isinstance(getattr(e, "bj", None), int):
                return f"{names[e.bi + 1]} - {names[e.bj + 1]}"
            return " - ".join(names[i + 1] for i in e.body_indices()) or "ground"

        elements = []
        for group, items in (
            ("joint", self.joints),
            ("driver", self.drivers),
            ("force", self.forces),
        ):
            for e in items:
                elements.append((group, e.name, type(e).__name__, between(e), _numbers(e)))
        return bodies, elements

    def __repr__(self) -> str:
        bodies, elements = self._rows()
        lines = [f"Model {self.summary()}"]
        for name, mass, inertia, q0, pts in bodies:
            lines.append(f"  body {name}: mass {mass}, inertia {inertia}, q0 {q0}; points {pts}")
        for group, name, kind, on, numbers in elements:
            lines.append(f"  {group} {name}: {kind} on {on}" + (f"; {numbers}" if numbers else ""))
        return "\n".join(lines)


def _num(x) -> str:
    return f"{float(np.asarray(x)):.6g}"


def _vec(x) -> str:
    return "[" + ", ".join(f"{v:.6g}" for v in np.asarray(x, dtype=float).ravel()) + "]"


def _numbers(element) -> str:
    """The numbers of an element (its array fields, laws' included), as ``name value``."""
    out = []
    for leaf_path, leaf in jax.tree_util.tree_leaves_with_path(element):
        arr = np.asarray(leaf)
        if arr.dtype.kind != "f" or arr.size > 6:
            continue
        key = jax.tree_util.keystr(leaf_path).lstrip(".").replace(".", " ")
        if key.split(" ")[0] in ("bi", "bj", "si", "sj", "u", "v"):
            continue
        out.append(f"{key} {_num(arr) if arr.ndim == 0 else _vec(arr)}")
    return ", ".join(out)


__all__ = ["GROUND_NAME", "Model"]
