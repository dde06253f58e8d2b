"""mixdyn's path synthesis on the four-bar path-generation cases recorded in tests/data.

Each case file (``fourbar_path_*.txt`` in the repository's ``tests/data``) holds the targets,
the timing (free, prescribed up to the start, prescribed from the ground link, or not stated),
the variables' bounds, the source's constraints (Grashof; a crank; the points in order),
where the source gives one, a design vector or a published linkage, whose error is computed
here as a reference, and the published errors a case file records (``published ERROR WHO``:
the error a paper reports for a method, with the paper, its table and the address it was read
at). Where a source states no bounds, ``UNSTATED`` sets them. ``md.synthesize`` gets the
targets, the timing, the bounds and the source's Grashof condition: ``grashof="grashof"``
(any link the shortest), or ``grashof="crank_rocker"`` where the source asks for a crank
(``grashof_crank``); its best linkage, and its best one that also meets the source's
constraints, are then measured here by a computation of their own (NumPy; the coupler point
from the two circles' intersection on the linkage's branch, not mixdyn's program): the sum of
squared distances from the coupler point at the linkage's input angles to the targets, the
sources' error. The table puts the smallest published error beside it ("not found" where the
case file records none).

How the sources' problems are stated in ``PathTask``, and what it cannot state:

* a length's lower bound of 0 becomes ``LENGTH_FLOOR`` (``PathTask`` wants lengths > 0);
* a fixed number (``x0 = y0 = theta0 = 0``) is a bound whose ends are equal;
* where the source prescribes the input angles from the ground link (``timing absolute``),
  ``PathTask`` takes them so (``timing_from="ground"``); the error at the source's own angles
  is measured here too (the linkage re-measured at the prescribed angles), a check that the
  search kept them;
* the points' order within a turn (``order``) is checked afterwards: the table says whether
  the best linkage meets the source's constraints and gives the best candidate that does.

Run: ``python benchmarks/synthesis_cases.py [--starts 2048] [--refdata DIR] [--case NAME]
[--chunk 512] [--warm]`` (``--refdata``: the folder of the case files, ``REFDATA`` by default;
``--chunk``: starts solved by one vectorized program, all of them at once on a GPU;
``--warm``: each search twice, the second's time too, its programs compiled).
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import operator
import pathlib
import platform
import time

import numpy as np

#: A length's lower bound where the source says 0 (PathTask's lengths are > 0).
LENGTH_FLOOR = 1e-3
#: Bounds where a source states none, in the targets' size (the largest distance from their
#: centre): lengths, coupler point and ground pivot's distance from the targets' centre (wider
#: than ``PathTask``'s defaults, 0.05-5, 5 and 3, so that the published linkages lie inside).
UNSTATED = {"lengths": (0.01, 10.0), "coupler": 10.0, "pivot": 6.0}
#: The four-bar's numbers in the order of ``mixdyn.synthesis.NAMES``.
NAMES = ("r1", "r2", "r3", "r4", "rcx", "rcy", "x0", "y0", "theta0")
#: The folder of the case files: the repository's ``tests/data``.
REFDATA = pathlib.Path(__file__).resolve().parents[1] / "tests" / "data"

_OPS = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
}


def number(text: str) -> float:
    """A number as the case files write it: ``20``, ``-2.5``, ``pi``, ``5*pi/12``."""

    def value(node):
        if isinstance(node, ast.Expression):
            return value(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, int | float):
            return float(node.value)
        if isinstance(node, ast.Name) and node.id == "pi":
            return np.pi
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            return -value(node.operand)
        if isinstance(node, ast.BinOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](value(node.left), value(node.right))
        raise ValueError(f"not a number of a case file: {text!r}")

    return value(ast.parse(text, mode="eval"))


@dataclasses.dataclass(frozen=True)
class Case:
    """A path-generation case as its file states it.

    Attributes:
        name: the file's stem.
        source: the file's first line (``# source: ...``).
        points: (N, 2) the targets.
        timing: ``"free"``, ``"step"`` (``theta2_i = theta2_1 + (i-1) step``),
            ``"absolute"`` (``theta2_i`` from the ground link) or ``"unstated"`` (the source
            does not say: searched as free).
        angles: the step (1,) or the absolute angles (N,) [rad]; empty when free.
        bounds: name -> (low, high) of the four-bar's numbers.
        fixed: name -> value of numbers that are not variables.
        constraints: ``"grashof"``, ``"grashof_crank"``, ``"order"``.
        design: the source's design vector, if it gives one (the source's variables).
        linkage: (9,) a published linkage in ``NAMES``' order, if the source gives one.
        published: (error, who) pairs: the errors papers report for this case, each with the
            method, the paper, its table and the address it was read at.
    """

    name: str
    source: str
    points: np.ndarray
    timing: str
    angles: np.ndarray
    bounds: dict
    fixed: dict
    constraints: frozenset
    design: np.ndarray | None
    linkage: np.ndarray | None
    published: tuple = ()


def from_four_bar_rs(p1x, p1y, a, l1, l2, l3, l4, l5, g) -> np.ndarray:
    """A four-bar-rs ``FourBar`` (``four-bar/src/mech/fb.rs``: crank pivot ``p1``, ground link
    ``l1`` at ``a``, crank ``l2``, coupler ``l3``, rocker ``l4``, coupler point ``l5`` from the
    crank pin at ``g`` from the coupler line) in ``NAMES``' order."""
    return np.array([l1, l2, l3, l4, l5 * np.cos(g), l5 * np.sin(g), p1x, p1y, a])


def read_case(path: pathlib.Path) -> Case:
    """The case in a ``fourbar_path_*.txt`` file."""
    lines = path.read_text(encoding="utf-8").splitlines()
    points, bounds, fixed, constraints = [], {}, {}, set()
    timing, angles, design, linkage, published = None, [], None, None, []
    for line in lines:
        if line.startswith("published "):  # free text after the error: keep its '#'s
            _, error, who = line.split(maxsplit=2)
            published.append((number(error), who))
            continue
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        key, rest = words[0], words[1:]
        if key == "point":
            points.append([number(w) for w in rest])
        elif key == "bound":
            bounds[rest[0]] = (number(rest[1]), number(rest[2]))
        elif key == "fixed":
            fixed[rest[0]] = number(rest[1])
        elif key == "constraint":
            constraints.add(rest[0])
        elif key == "timing":
            timing, angles = rest[0], [number(w) for w in rest[1:]]
        elif key == "design":
            design = np.array([number(w) for w in rest])
        elif key == "linkage_fourbar_rs":
            linkage = from_four_bar_rs(*(number(w) for w in rest))
    if timing not in ("free", "step", "absolute", "unstated"):
        raise ValueError(f"{path.name}: no timing line (free, step, absolute or unstated)")
    return Case(
        name=path.stem,
        source=lines[0],
        points=np.array(points, dtype=float),
        timing=timing,
        angles=np.array(angles, dtype=float),
        bounds=bounds,
        fixed=fixed,
        constraints=frozenset(constraints),
        design=design,
        linkage=linkage,
        published=tuple(published),
    )


def path_task(case: Case):
    """The case as a ``mixdyn.synthesis.PathTask`` (see the module's notes on what differs)."""
    from mixdyn.synthesis import PathTask

    size = np.max(np.linalg.norm(case.points - case.points.mean(axis=0), axis=1))
    centre = case.points.mean(axis=0)
    bounds = {}
    if not case.bounds:  # none stated: wider than PathTask's defaults (see UNSTATED)
        lo, hi = UNSTATED["lengths"]
        bounds = {n: (lo * size, hi * size) for n in ("r1", "r2", "r3", "r4")}
        bounds |= {
            n: (-UNSTATED["coupler"] * size, UNSTATED["coupler"] * size) for n in ("rcx", "rcy")
        }
        for n, c in (("x0", centre[0]), ("y0", centre[1])):
            bounds[n] = (c - UNSTATED["pivot"] * size, c + UNSTATED["pivot"] * size)
    for name, (lo, hi) in case.bounds.items():
        if name not in NAMES:
            continue  # the input angles: a turn, which PathTask's angles span anyway
        if name in ("r1", "r2", "r3", "r4"):
            lo = max(lo, LENGTH_FLOOR)
        bounds[name] = (lo, hi)
    for name, v in case.fixed.items():
        bounds[name] = (v, v)  # PathTask: equal ends fix the number
    timing = None
    if case.timing == "step":
        timing = case.angles[0] * np.arange(len(case.points))
    elif case.timing == "absolute":
        timing = case.angles
    grashof = "any"
    if "grashof_crank" in case.constraints:
        grashof = "crank_rocker"
    elif "grashof" in case.constraints:
        grashof = "grashof"
    timing_from = "ground" if case.timing == "absolute" else "first"
    return PathTask(
        case.points, timing=timing, bounds=bounds, grashof=grashof, timing_from=timing_from
    )


def coupler_points(v, branch: float, theta2) -> tuple[np.ndarray, np.ndarray]:
    """The coupler point (K, 2) at the input angles ``theta2`` (K,) of the four-bar ``v``
    (``NAMES``' order) on ``branch`` (the side of the line from the crank pin to the rocker's
    pivot where the rocker pin lies), and whether the loop closes there (K,). The rocker pin
    is the intersection of the circles about the crank pin (radius r3) and about the rocker's
    pivot (radius r4)."""
    r1, r2, r3, r4, rcx, rcy, x0, y0, theta0 = (float(x) for x in v)
    theta2 = np.asarray(theta2, dtype=float)
    o2 = np.array([x0, y0])
    o4 = o2 + r1 * np.array([np.cos(theta0), np.sin(theta0)])
    a = o2 + r2 * np.stack([np.cos(theta0 + theta2), np.sin(theta0 + theta2)], axis=-1)
    d = o4 - a
    dist = np.linalg.norm(d, axis=-1)
    closes = (dist <= r3 + r4) & (dist >= abs(r3 - r4))
    along = (r3**2 - r4**2 + dist**2) / (2 * dist)
    h = np.sqrt(np.maximum(r3**2 - along**2, 0.0))
    u = d / dist[:, None]
    b = a + along[:, None] * u + branch * h[:, None] * np.stack([-u[:, 1], u[:, 0]], axis=-1)
    e3 = (b - a) / r3
    c = a + rcx * e3 + rcy * np.stack([-e3[:, 1], e3[:, 0]], axis=-1)
    return c, closes


def path_error(case: Case, v, branch: float, theta2) -> float:
    """The sources' error: ``sum_i |C(theta2_i) - P_i|^2`` (inf where the loop opens at a
    target)."""
    c, closes = coupler_points(v, branch, theta2)
    if not np.all(closes):
        return float("inf")
    return float(np.sum((c - case.points) ** 2))


def reference_error(case: Case) -> tuple[float | None, str]:
    """The error of the source's design or published linkage, computed here, on the branch
    where it is smaller: at the design's own input angles; with a timing step, at its best
    start (a grid of 3600 starts refined by Brent's method); with timing from the ground
    link, at those angles; timing-free, the nearest coupler point to each target (20,000
    input angles), a lower bound of its timing-free error (equal where the nearest points come
    in order). Returns the error (None without a design or linkage) and how it was measured."""
    from scipy.optimize import minimize_scalar

    n = len(case.points)
    if case.design is not None:
        theta2 = case.design[9 : 9 + n]
        return min(path_error(case, case.design[:9], b, theta2) for b in (1.0, -1.0)), "own angles"
    if case.linkage is None:
        return None, ""
    v = case.linkage
    if case.timing == "absolute":
        return min(path_error(case, v, b, case.angles) for b in (1.0, -1.0)), "source's angles"
    if case.timing == "step":
        best = np.inf
        for b in (1.0, -1.0):

            def f(t0, b=b):
                return min(path_error(case, v, b, t0 + case.angles[0] * np.arange(n)), 1e300)

            starts = np.linspace(0.0, 2 * np.pi, 3600, endpoint=False)
            t0 = starts[int(np.argmin([f(t) for t in starts]))]
            found = minimize_scalar(
                f, bounds=(t0 - 2e-3, t0 + 2e-3), method="bounded", options={"xatol": 1e-12}
            )
            best = min(best, found.fun)
        return float(best), "best start"
    grid = np.linspace(0.0, 2 * np.pi, 20_000, endpoint=False)
    best = np.inf
    for b in (1.0, -1.0):
        c, closes = coupler_points(v, b, grid)
        d2 = np.sum((c[None] - case.points[:, None]) ** 2, axis=2)
        d2[:, ~closes] = np.inf
        best = min(best, float(np.sum(d2.min(axis=1))))
    return best, "nearest points"


def meets(case: Case, v, theta2) -> bool:
    """Whether a linkage meets the source's constraints: Grashof (shortest + longest <= the
    other two), with the crank the shortest where asked, and the input angles in cyclic order
    within a turn where asked."""
    links = np.asarray(v[:4], dtype=float)
    ok = True
    if case.constraints & {"grashof", "grashof_crank"}:
        ok &= links.min() + links.max() <= links.sum() - links.min() - links.max()
    if "grashof_crank" in case.constraints:
        ok &= int(np.argmin(links)) == 1
    if "order" in case.constraints:
        steps = np.diff(np.asarray(theta2, dtype=float))
        ok &= bool(np.all(steps > 0)) and theta2[-1] - theta2[0] <= 2 * np.pi + 1e-9
    return bool(ok)


def measure(case: Case, candidate) -> dict:
    """A candidate's error at its own input angles and, for timing prescribed from the ground
    link, at the source's angles; whether it meets the source's constraints."""
    v = np.array([float(getattr(candidate.fourbar, n)) for n in NAMES])
    branch = float(candidate.fourbar.branch)
    out = {
        "error": path_error(case, v, branch, candidate.angles),
        "meets": meets(case, v, candidate.angles),
        "start": float(candidate.angles[0]),
    }
    if case.timing == "absolute":
        out["error_prescribed"] = path_error(case, v, branch, case.angles)
    return out


def run(case: Case, starts: int, seed: int, chunk: int = 512, warm: bool = False) -> dict:
    """``md.synthesize`` on the case (``chunk`` starts a vectorized program); the best
    candidate and the best one that meets the source's constraints, measured by
    :func:`measure`. ``warm``: searched twice, the second search's time given too (its
    programs compiled by the first)."""
    import mixdyn as md

    search = md.synthesis.SearchSettings(starts=starts, seed=seed, chunk=chunk, keep=100)
    started = time.perf_counter()
    out = md.synthesize(path_task(case), search=search)
    seconds = time.perf_counter() - started
    if warm:
        started = time.perf_counter()
        out = md.synthesize(path_task(case), search=search)
        seconds = (seconds, time.perf_counter() - started)
    measured = [measure(case, c) for c in out.candidates]
    best = measured[0] if measured else None
    meeting = [m for m in measured if m["meets"]]
    return {
        "best": best,
        "best_meeting": min(meeting, key=lambda m: m["error"]) if meeting else None,
        "feasible": out.feasible,
        "seconds": seconds,
    }


def _fmt(x) -> str:
    return "-" if x is None else f"{x:.4g}"


def _timing(case: Case) -> str:
    degrees = np.round(np.rad2deg(case.angles), 2)
    if case.timing == "step":
        return f"prescribed, steps of {degrees[0]:g} deg"
    if case.timing == "absolute":
        return "prescribed from the ground link, " + ", ".join(f"{d:g}" for d in degrees) + " deg"
    return {"free": "free", "unstated": "not stated (searched free)"}[case.timing]


def _error(m: dict | None) -> str:
    if m is None:
        return "-"
    if "error_prescribed" in m:
        return f"{_fmt(m['error'])} (at the source's angles: {_fmt(m['error_prescribed'])})"
    return _fmt(m["error"])


def _published(case: Case, meeting: dict | None) -> str:
    """The smallest published error with who reported it, and mixdyn's best linkage that meets
    the source's constraints as a multiple of it (at the source's own input angles where the
    source prescribes them from the ground link: the error the papers report)."""
    if not case.published:
        return "not found"
    error, who = min(case.published, key=lambda p: p[0])
    text = f"{_fmt(error)} ({who})"
    if meeting is not None:
        ours = meeting.get("error_prescribed", meeting["error"])
        text += f"; mixdyn / published = {ours / error:.3g}"
    return text


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=2048)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--chunk", type=int, default=512, help="starts a vectorized program")
    parser.add_argument("--warm", action="store_true", help="search twice: time the second too")
    parser.add_argument(
        "--refdata", type=pathlib.Path, default=REFDATA, help="the case files' folder"
    )
    parser.add_argument("--case", action="append", help="a file's stem (default: all)")
    args = parser.parse_args()
    files = sorted(args.refdata.glob("fourbar_path_*.txt"))
    if args.case:
        files = [f for f in files if f.stem in args.case]
    if not files:  # a named input error (exit 2) before importing or computing anything
        which = f" named {', '.join(args.case)}" if args.case else ""
        parser.error(f"no case file fourbar_path_*.txt{which} in {args.refdata} (see --refdata)")
    import jax

    print(f"{platform.processor() or platform.machine()}, JAX on {jax.devices()[0].platform}, "
          f"{args.starts} starts, seed {args.seed} (times include compiling)\n")  # fmt: skip
    print(
        "| case | targets | timing | published best error | the source's design or published "
        "linkage, its error computed here | mixdyn's best: error | source's constraints | "
        "mixdyn's best meeting them: error | feasible / starts | search [s] |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    total = time.perf_counter()
    for path in files:
        case = read_case(path)
        result = run(case, args.starts, args.seed, args.chunk, args.warm)
        sec = result["seconds"]
        sec = f"{sec[0]:.1f} (warm {sec[1]:.2f})" if args.warm else f"{sec:.1f}"
        ref, how = reference_error(case)
        best, meeting = result["best"], result["best_meeting"]
        if not case.constraints:
            met = "none stated"
        else:
            met = "met" if best and best["meets"] else "not met"
        print(
            f"| {case.name} | {len(case.points)} | {_timing(case)} | {_published(case, meeting)} "
            f"| {_fmt(ref)}{f' ({how})' if how else ''} | {_error(best)} | {met} | "
            f"{_error(meeting)} | {result['feasible']} / {args.starts} | "
            f"{sec} |"
        )
    print(f"\nall cases: {time.perf_counter() - total:.0f} s")


if __name__ == "__main__":
    main()
