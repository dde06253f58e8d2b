"""Elliptic Fourier descriptors of a closed curve, normalised for position, size, orientation
and starting point (Kuhl and Giardina, 1982).

A closed curve ``(x(l), y(l))`` of perimeter ``L``, ``l`` its arc length from a starting point,
is the series (Kuhl and Giardina's eq. 6 and 7)

    ``x(l) = A0 + sum_n a_n cos(2 pi n l / L) + b_n sin(2 pi n l / L)``
    ``y(l) = C0 + sum_n c_n cos(2 pi n l / L) + d_n sin(2 pi n l / L)``

with ``a_n = (2/L) int x cos(2 pi n l / L) dl`` and likewise ``b_n`` (sine), ``c_n``, ``d_n``
(``y``); ``(A0, C0)`` is the curve's mean point over its arc length. Each harmonic is an
ellipse; the descriptors depend on the curve's geometry alone, not on how it was sampled.

Computed here by spectral quadrature from ``K`` samples ``z_k = z(t_k)``, ``t_k = 2 pi k /
K``, of the curve at even steps of any smooth periodic parameter ``t`` (a crank angle, an
index): the velocity ``z'(t)`` from the samples' FFT, the speed ``|z'|``, the arc length
``l(t)`` by integrating the speed's Fourier series, then ``a_n = (2/L) sum_k x_k cos(2 pi n
l_k / L) |z'_k| 2 pi / K`` (the trapezoid rule, spectrally accurate for smooth periodic
integrands). Kuhl and Giardina's own formulas integrate the polygon through the points
exactly (a chain code); those of a smooth curve sampled at ``K`` points differ from the
curve's by ``O(1/K^2)``, these by far less. Everything is an explicit function of the samples
(``jax.numpy``), differentiable.

Normalisation (Kuhl and Giardina, section 4; also ``pyefd.normalize_efd``): the starting point
moved to an end of the first harmonic's major axis, ``theta1 = atan2(2 (a1 b1 + c1 d1), a1^2
- b1^2 + c1^2 - d1^2) / 2``, every harmonic turned by ``n theta1``: ``[a* b*; c* d*]_n = [a b;
c d]_n R(n theta1)``; then the major axis turned onto x, ``psi1 = atan2(c1*, a1*)``, and the
size divided out, ``E = |(a1*, c1*)|`` (the first harmonic's semi-major axis):
``N_n = R(-psi1) [a* b*; c* d*]_n / E``. The first harmonic becomes ``[1 0; 0 +-b/a]``
(the sign: the sense the curve runs). The two ends of the major axis give two such
normalisations, which differ by ``(-1)^(n+1)`` on harmonic ``n`` (:func:`flipped`); a
comparison takes the nearer one.

Used for four-bar path synthesis by Chang, Chang and Lee (J. Mech. Sci. Technol., 2024,
doi:10.1007/s12206-024-0436-y; the ``four_bar`` and ``efd`` crates).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np


def _safe_angle(y, x):
    """``atan2(y, x)`` with finite derivatives where ``x = y = 0`` (0 there)."""
    tiny = (x * x + y * y) < 1e-300
    return jnp.arctan2(jnp.where(tiny, 0.0, y), jnp.where(tiny, 1.0, x))


def _wavenumbers(k: int) -> np.ndarray:
    """(k,) the FFT's integer wavenumbers, the unresolved Nyquist one (even ``k``) zero."""
    w = np.fft.fftfreq(k, 1.0 / k)
    if k % 2 == 0:
        w[k // 2] = 0.0
    return w


@dataclasses.dataclass(frozen=True)
class Descriptors:
    """A closed curve's elliptic Fourier descriptors (a PyTree of arrays).

    Attributes:
        coefficients: (H, 2, 2) ``[[a_n, b_n], [c_n, d_n]]`` for ``n = 1..H`` [length].
        centre: (2,) ``(A0, C0)``, the mean point over the arc length [length].
        perimeter: ``L`` [length].
    """

    coefficients: jax.Array
    centre: jax.Array
    perimeter: jax.Array


jax.tree_util.register_dataclass(
    Descriptors, data_fields=["coefficients", "centre", "perimeter"], meta_fields=[]
)


def describe(samples, harmonics: int) -> Descriptors:
    """The first ``harmonics`` elliptic Fourier descriptors of the closed curve through
    ``samples`` (K, 2) [length], taken at even steps of a smooth periodic parameter (the first
    sample is not repeated at the end); K above twice the harmonics (more: more accurate)."""
    z = jnp.asarray(samples, dtype=jnp.float64)
    k = z.shape[0]
    w = jnp.asarray(_wavenumbers(k))
    dt = 2.0 * np.pi / k
    velocity = jnp.real(jnp.fft.ifft(1j * w[:, None] * jnp.fft.fft(z, axis=0), axis=0))
    speed = jnp.sqrt(jnp.sum(velocity**2, axis=1) + 1e-300)
    perimeter = jnp.sum(speed) * dt
    spectrum = jnp.fft.fft(speed)
    integrated = jnp.where(w == 0, 0.0, spectrum / (1j * jnp.where(w == 0, 1.0, w)))
    periodic = jnp.real(jnp.fft.ifft(integrated))  # the speed's integral less its mean rate
    t = jnp.arange(k) * dt
    length = perimeter * t / (2.0 * np.pi) + periodic - periodic[0]
    phase = 2.0 * np.pi * length / perimeter
    n = jnp.arange(1, harmonics + 1, dtype=jnp.float64)
    weight = speed * dt * 2.0 / perimeter
    cos, sin = jnp.cos(n[:, None] * phase), jnp.sin(n[:, None] * phase)
    x, y = z[:, 0] * weight, z[:, 1] * weight
    coefficients = jnp.stack(
        [jnp.stack([cos @ x, sin @ x], axis=-1), jnp.stack([cos @ y, sin @ y], axis=-1)], axis=1
    )
    centre = jnp.sum(z * speed[:, None], axis=0) * dt / perimeter
    return Descriptors(coefficients, centre, perimeter)


def _rotation(angle):
    c, s = jnp.cos(angle), jnp.sin(angle)
    return jnp.stack([jnp.stack([c, -s], axis=-1), jnp.stack([s, c], axis=-1)], axis=-2)


@dataclasses.dataclass(frozen=True)
class Normalised:
    """Normalised descriptors and what the normalisation took out (a PyTree of arrays).

    Attributes:
        coefficients: (H, 2, 2) ``N_n`` (dimensionless).
        size: ``E``, the first harmonic's semi-major axis [length].
        orientation: ``psi1`` [rad], its major axis's angle.
        start: ``theta1`` [rad], the starting point's shift (in ``2 pi l / L``).
        centre: (2,) ``(A0, C0)`` [length].
    """

    coefficients: jax.Array
    size: jax.Array
    orientation: jax.Array
    start: jax.Array
    centre: jax.Array


jax.tree_util.register_dataclass(
    Normalised,
    data_fields=["coefficients", "size", "orientation", "start", "centre"],
    meta_fields=[],
)


def normalise(d: Descriptors) -> Normalised:
    """The descriptors ``d`` normalised for starting point, orientation, size and position
    (Kuhl and Giardina; the module's formulas)."""
    m = d.coefficients
    (a1, b1), (c1, d1) = m[0, 0], m[0, 1]
    theta1 = 0.5 * _safe_angle(2.0 * (a1 * b1 + c1 * d1), a1**2 - b1**2 + c1**2 - d1**2)
    n = jnp.arange(1, m.shape[0] + 1, dtype=jnp.float64)
    started = m @ _rotation(n * theta1)
    psi1 = _safe_angle(started[0, 1, 0], started[0, 0, 0])
    size = jnp.sqrt(started[0, 0, 0] ** 2 + started[0, 1, 0] ** 2 + 1e-300)
    coefficients = _rotation(-psi1) @ started / size
    return Normalised(coefficients, size, psi1, theta1, d.centre)


def flipped(coefficients) -> jax.Array:
    """(H, 2, 2) the other normalisation of ``coefficients`` (H, 2, 2): the starting point at
    the major axis's other end, ``(-1)^(n+1) N_n``."""
    n = np.arange(1, coefficients.shape[0] + 1)
    return coefficients * jnp.asarray((-1.0) ** (n + 1))[:, None, None]


def shape_gap(candidate: Normalised, target: Normalised) -> tuple[jax.Array, jax.Array]:
    """``(N_c - N_t (H, 2, 2), flip)``: the candidate's normalised descriptors less the
    target's, the candidate's normalisation the nearer of its two (``flip`` 1.0 where the
    other end of its major axis, else 0.0)."""
    straight = candidate.coefficients - target.coefficients
    other = flipped(candidate.coefficients) - target.coefficients
    flip = jnp.sum(other**2) < jnp.sum(straight**2)
    return jnp.where(flip, other, straight), flip.astype(jnp.float64)


def shape_error(candidate: Normalised, target: Normalised) -> jax.Array:
    """``sum_n |N_n(candidate) - N_n(target)|^2`` over the four entries of each harmonic
    (dimensionless), the candidate's nearer normalisation (:func:`shape_gap`)."""
    gap, _ = shape_gap(candidate, target)
    return jnp.sum(gap**2)


def similarity(candidate: Normalised, target: Normalised, flip) -> tuple:
    """``(scale, angle [rad], shift (2,) [length])`` of the similarity ``p -> scale R(angle)
    p + shift`` that carries the candidate's curve onto the target's where their normalised
    descriptors agree (``flip`` from :func:`shape_gap`): ``scale = E_t / E_c``, ``angle =
    psi1_t - psi1_c (- pi where flipped)``, the mean points onto each other."""
    scale = target.size / candidate.size
    angle = target.orientation - candidate.orientation - np.pi * flip
    shift = target.centre - scale * _rotation(angle) @ candidate.centre
    return scale, angle, shift


def resample(points, count: int) -> np.ndarray:
    """(count, 2) the closed curve through ``points`` (N, 2), taken at even steps of one
    parameter, resampled at ``count`` even steps of it by its trigonometric interpolant (the
    FFT zero-padded; the Nyquist term of an even N split in two)."""
    p = np.asarray(points, dtype=float)
    n = len(p)
    spectrum = np.fft.fft(p, axis=0)
    out = np.zeros((count, 2), dtype=complex)
    half = (n - 1) // 2
    out[: half + 1] = spectrum[: half + 1]
    out[count - half :] = spectrum[n - half :]
    if n % 2 == 0:
        out[n // 2] += spectrum[n // 2] / 2
        out[count - n // 2] += spectrum[n // 2] / 2
    return np.real(np.fft.ifft(out, axis=0)) * count / n


__all__ = [
    "Descriptors",
    "Normalised",
    "describe",
    "flipped",
    "normalise",
    "resample",
    "shape_error",
    "shape_gap",
    "similarity",
]
