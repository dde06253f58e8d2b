"""Compliant contact laws: the normal force of two touching bodies from their penetration, and
a regularized Coulomb friction force (pure JAX functions of numbers).

Normal force (a Hertz law with hysteresis damping)::

    F = K delta**n (1 + c(e) delta_dot / v_ref),   F >= 0,   n = 3/2,

``delta`` the penetration [length] (contact while ``delta > 0``), ``delta_dot`` its rate
(positive while the bodies approach), ``K`` the Hertz stiffness (:func:`hertz_stiffness`),
``e`` the coefficient of restitution and ``c(e)`` the model's damping factor
(:data:`DAMPING_FACTORS`):

- ``hunt_crossley``: ``c = 3 (1 - e) / 2`` (Hunt and Crossley, "Coefficient of restitution
  interpreted as damping in vibroimpact", J. Appl. Mech. 42 (1975) 440-445);
- ``lankarani_nikravesh``: ``c = 3 (1 - e**2) / 4`` (Lankarani and Nikravesh, "A contact force
  model with hysteresis damping for impact analysis of multibody systems", J. Mech. Des. 112
  (1990) 369-376). Derived for a small loss of energy: accurate for ``e`` close to 1;
- ``flores``: ``c = 8 (1 - e) / (5 e)`` (Flores, Machado, Silva and Martins, "On the
  continuous contact force models for soft materials in multibody dynamics", Multibody Syst.
  Dyn. 25 (2011) 357-375), for any ``e`` in (0, 1], low restitution included.

In those papers ``v_ref`` is the initial impact speed ``delta_dot(-)``, a number each impact
stores. A force here is a pure function of the state, so ``v_ref`` is a parameter of the
contact (``impact_speed``): the damping coefficient ``chi = c(e) K / v_ref`` is a constant of
the contact, the stateless form of Hunt and Crossley's law that Marhefka and Orin use
("A compliant contact model with nonlinear damping for simulation of robotic systems", IEEE
Trans. SMC-A 29 (1999) 566-572; Drake's ``hunt_crossley_dissipation`` is ``c(e) / v_ref``
[time/length]). An impact at the speed ``v_ref`` rebounds with the published model's
restitution; at another speed ``v`` the loss of energy scales with the speed (to first order
``1 - e(v)**2 = (1 - e**2) v / v_ref``). The force vanishes with its first derivative at
``delta = 0`` (``n >= 1``) and is clamped at zero where the damping would pull (late in the
restitution phase), so that it is continuous for the adaptive integrators and for gradients.

Friction (regularized Coulomb): ``F_t = -mu F tanh(v_t / v_stick)``, ``v_t`` the sliding
speed at the contact point; below ``v_stick`` the friction grows linearly with the speed (a
creep instead of sticking), so that the force is smooth. ``mu`` and ``v_stick`` are the names
of the joint friction's coefficient and stick band (:class:`~mixdyn.JointFriction`).
"""

from __future__ import annotations

import jax.numpy as jnp

#: The exponent of the Hertz law (circles and cylinders in line contact, as in the papers).
HERTZ_EXPONENT = 1.5

#: The contact models by file name: their damping factor ``c(e)`` (see the module).
DAMPING_FACTORS = {
    "hunt_crossley": lambda e: 1.5 * (1.0 - e),
    "lankarani_nikravesh": lambda e: 0.75 * (1.0 - e**2),
    "flores": lambda e: 1.6 * (1.0 - e) / e,
}


def effective_modulus(young_modulus, poisson):
    """``E* = E / (2 (1 - nu**2))`` [pressure] of two bodies of one material (Hertz:
    ``1 / E* = (1 - nu_i**2) / E_i + (1 - nu_j**2) / E_j``)."""
    return young_modulus / (2.0 * (1.0 - poisson**2))


def hertz_stiffness(young_modulus, poisson, radius):
    """Hertz's stiffness ``K = (4/3) E* sqrt(R*)`` [force / length**1.5] for the effective
    radius ``R*`` [length] of the pair (``1 / R* = 1 / R_i + 1 / R_j``; a line has an
    infinite radius; a hole a negative one: a journal of radius ``R_j`` in a bearing of
    radius ``R_j + c`` has ``R* = R_j (R_j + c) / c``), as Lankarani and Nikravesh (1990) and
    Flores et al. (2006) write it: ``K = 4 / (3 (sigma_i + sigma_j)) sqrt(R*)``,
    ``sigma = (1 - nu**2) / E``."""
    return 4.0 / 3.0 * effective_modulus(young_modulus, poisson) * jnp.sqrt(radius)


def normal_force(delta, delta_dot, stiffness, restitution, impact_speed, model: str):
    """The normal force ``K delta**1.5 (1 + c(e) delta_dot / v_ref)`` [force], zero out of
    contact (``delta <= 0``) and where the damping would pull (clamped at 0); see the
    module. ``impact_speed`` ``v_ref`` [velocity] is unused where ``e = 1``."""
    d = jnp.maximum(delta, 0.0)
    damping = DAMPING_FACTORS[model](restitution) / impact_speed
    return jnp.maximum(stiffness * d**HERTZ_EXPONENT * (1.0 + damping * delta_dot), 0.0)


def elastic_energy(delta, stiffness):
    """The energy stored by the elastic part, ``K delta**2.5 / 2.5`` [energy] (0 out of
    contact): the potential of the contact force without damping."""
    d = jnp.maximum(delta, 0.0)
    return stiffness * d ** (HERTZ_EXPONENT + 1.0) / (HERTZ_EXPONENT + 1.0)


def friction_force(normal, sliding_speed, mu, v_stick):
    """The regularized Coulomb friction ``-mu N tanh(v_t / v_stick)`` [force] opposing the
    sliding speed ``v_t`` [velocity] (see the module)."""
    return -mu * normal * jnp.tanh(sliding_speed / v_stick)


__all__ = [
    "DAMPING_FACTORS",
    "HERTZ_EXPONENT",
    "effective_modulus",
    "elastic_energy",
    "friction_force",
    "hertz_stiffness",
    "normal_force",
]
