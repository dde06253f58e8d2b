"""What the path and the function searches share: their penalties and margins, the batched
Levenberg-Marquardt solve of many starts, the loop over chunks of starts with progress, the
distinct outcomes best first, and the ranked result's best candidate."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError

#: The penalties' weight (residuals of infeasibility times this).
PENALTY = 10.0
#: The weight of a path search's penalties on its numbers' bounds: an outcome whose best
#: lies past a bound settles this much more closely against it (its overshoot ~ 1 /
#: weight^2), and is then taken onto it exactly (``_search._kept_within``).
BOUND_PENALTY = 1e3
#: The largest |cos mu| a search aims at (a margin inside the loop's closure).
CLOSURE_MARGIN = 0.999
#: Input angles of the exact check of closure along the traversed motion.
CHECK_SAMPLES = 1024


class Ranked:
    """A search's result: ``candidates`` ranked best first, out of ``starts``."""

    @property
    def best(self):
        """The best candidate; a :class:`~mixdyn.errors.ModelError` where none is feasible."""
        if not self.candidates:
            title = getattr(getattr(self.task, "linkage", None), "TITLE", "four-bar")
            raise ModelError(
                f"no feasible {title} among {self.starts} starts: give more starts, wider "
                "bounds or a smaller min_transmission",
                "synthesize",
            )
        return self.candidates[0]


def levenberg_marquardt(residuals, max_steps: int):
    """``(u (C, size), branches (C,)) -> (u, sum of squared residuals (C,))``: every start
    solved by optimistix' Levenberg-Marquardt (to be vectorized and compiled by the caller)."""
    import optimistix as optx

    solver = optx.LevenbergMarquardt(rtol=1e-10, atol=1e-12)

    def one(u, branch):
        sol = optx.least_squares(
            residuals, solver, u, args=branch, max_steps=max_steps, throw=False
        )
        return sol.value, jnp.sum(residuals(sol.value, branch) ** 2)

    return jax.vmap(one)


def solve_all(solve_chunk, u0, branches, chunk, progress):
    """Every start ``u0`` (S, size) solved, ``chunk`` at a time by ``solve_chunk(u (chunk,
    size), branches (chunk,)) -> (u, sums of squared residuals)`` (one vectorized program, the
    last chunk padded); ``(u (S, size), sums (S,))``, ``progress(done, total, best)`` after
    each chunk."""
    total = len(u0)
    us, scores, best = [], [], np.inf
    for lo in range(0, total, chunk):
        hi = min(lo + chunk, total)
        pad = chunk - (hi - lo)
        batch = np.concatenate([u0[lo:hi], np.repeat(u0[lo : lo + 1], pad, axis=0)])
        bb = np.concatenate([branches[lo:hi], np.repeat(branches[lo : lo + 1], pad)])
        u, sc = solve_chunk(batch, bb)
        us.append(np.asarray(u)[: hi - lo])
        scores.append(np.asarray(sc)[: hi - lo])
        if np.any(np.isfinite(scores[-1])):
            best = min(best, float(np.nanmin(scores[-1])))
        if progress is not None:
            progress(hi, total, best)
    return np.concatenate(us), np.concatenate(scores)


def distinct(ok, scores, keys, branches, tol: float):
    """The indices of the feasible outcomes (``ok`` (C,)), least ``scores`` (C,) first, whose
    ``keys`` (C, k) differ by ``tol`` or more (largest component) from every one before on the
    same branch: the same linkage reached from two starts is kept once. A generator: a caller
    stops at its count."""
    seen = []
    for i in np.argsort(np.where(ok, scores, np.inf))[: int(np.sum(ok))]:
        if any(np.max(np.abs(keys[i] - k)) < tol and b == branches[i] for k, b in seen):
            continue  # the same linkage from another start
        seen.append((keys[i], branches[i]))
        yield i


__all__ = [
    "BOUND_PENALTY",
    "CHECK_SAMPLES",
    "CLOSURE_MARGIN",
    "PENALTY",
    "Ranked",
    "distinct",
    "levenberg_marquardt",
    "solve_all",
]
