"""``mixdyn check`` on generated pendulum chains: wall time and peak memory against size.

Writes a model file per size (a chain of ``N`` links of 1 m joined by revolute joints, the
first pinned to the ground, each link at a slight angle, with a forward run and a kinematic
run driving every joint angle in the small case), then runs ``mixdyn check FILE`` under
``/usr/bin/time -v`` and prints a table of wall time [s] and peak resident memory [MB].
With ``--phases`` it also times, in a separate process, reading the file
(:func:`mixdyn.io.read`: YAML and the schema) and building the model (:func:`mixdyn.io.build`:
names, units, expressions), the part of ``check`` before any analysis.

Run: ``python benchmarks/check_scaling.py [--sizes 1000 2000 5000 10000] [--keep DIR]
[--phases]``.
"""

from __future__ import annotations

import argparse
import math
import os
import pathlib
import re
import subprocess
import sys
import tempfile


def chain_yaml(n: int, link: float = 1.0, theta: float = 0.3) -> str:
    """A model file (YAML text) of a chain of ``n`` links pinned end to end.

    Args:
        n: number of links (bodies).
        link: link length [m].
        theta: angle of every link from the downward vertical [rad].

    Returns:
        The file's text, with one forward run (``swing``).
    """
    s, c = math.sin(theta), math.cos(theta)
    lines = [
        "mixdyn: 1",
        f"name: chain{n}",
        "units: {length: m, mass: kg, time: s}",
        "gravity: [0, -9.81]",
        "bodies:",
    ]
    for k in range(n):
        # centre of link k: the end of link k - 1 plus half a link
        x = (k + 0.5) * link * s
        y = -(k + 0.5) * link * c
        lines.append(
            f"  - {{name: l{k}, mass: 1 kg, inertia: 0.0833 kg*m**2, "
            f"q0: [{x:.12g}, {y:.12g}, {theta}], "
            f"points: {{top: [0, {link / 2}], bottom: [0, {-link / 2}]}}}}"
        )
    lines.append("joints:")
    lines.append("  - {type: revolute, name: j0, point_i: ground, point_j: l0.top}")
    for k in range(1, n):
        lines.append(
            f"  - {{type: revolute, name: j{k}, point_i: l{k - 1}.bottom, point_j: l{k}.top}}"
        )
    lines += [
        "runs:",
        "  - name: swing",
        "    kind: forward",
        "    time: {span: [0, 1], n: 11}",
    ]
    return "\n".join(lines) + "\n"


def measure(path: pathlib.Path, mixdyn: str) -> tuple[float, float, int]:
    """``(wall time [s], peak RSS [MB], exit status)`` of ``mixdyn check path``."""
    out = subprocess.run(
        ["/usr/bin/time", "-v", mixdyn, "check", str(path)],
        capture_output=True,
        text=True,
    )
    err = out.stderr
    wall = re.search(r"Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)", err)
    h, mnt, sec = wall.groups()
    secs = int(h or 0) * 3600 + int(mnt) * 60 + float(sec)
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", err).group(1)) / 1024
    if out.returncode != 0:
        sys.stderr.write(out.stdout[-2000:] + err[-2000:])
    return secs, rss, out.returncode


_PHASES = """\
import sys, time
import mixdyn.io as mio
t0 = time.perf_counter()
spec = mio.read(sys.argv[1])
t1 = time.perf_counter()
mio.build(spec)
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""


def phases(path: pathlib.Path, python: str = sys.executable) -> tuple[float, float]:
    """``(read [s], build [s])`` of ``path`` in a fresh process (imports not counted)."""
    out = subprocess.run(
        [python, "-c", _PHASES, str(path)], capture_output=True, text=True, check=True
    )
    read, build = out.stdout.split()[-2:]
    return float(read), float(build)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 2000, 5000, 10000])
    ap.add_argument("--keep", type=pathlib.Path, help="folder to keep the model files in")
    ap.add_argument(
        "--mixdyn",
        default=os.path.join(os.path.dirname(sys.executable), "mixdyn"),
        help="the mixdyn command",
    )
    ap.add_argument(
        "--phases", action="store_true", help="also time reading and building the model"
    )
    args = ap.parse_args()
    folder = args.keep or pathlib.Path(tempfile.mkdtemp(prefix="check_scaling_"))
    folder.mkdir(parents=True, exist_ok=True)
    extra = f" {'read s':>7} {'build s':>7}" if args.phases else ""
    print(f"{'bodies':>8} {'file MB':>8}{extra} {'wall s':>8} {'peak MB':>9} {'exit':>5}")
    for n in args.sizes:
        path = folder / f"chain{n}.yaml"
        path.write_text(chain_yaml(n))
        if args.phases:
            read, build = phases(path)
            extra = f" {read:>7.2f} {build:>7.2f}"
        secs, rss, rc = measure(path, args.mixdyn)
        size = path.stat().st_size / 1e6
        print(f"{n:>8} {size:>8.2f}{extra} {secs:>8.1f} {rss:>9.0f} {rc:>5}", flush=True)


if __name__ == "__main__":
    main()
