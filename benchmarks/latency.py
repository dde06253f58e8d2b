"""Latency of a model-file run and of a second Python process.

Times whole processes (wall clock, ``time.perf_counter`` around ``subprocess.run``), each
scenario ``--repeat`` times, and prints the median, min and max, the target and the ratio
median / target; with ``--baseline REV`` the same scenarios on a checkout of ``REV`` (a
temporary ``git worktree``, put first on ``PYTHONPATH``) and the ratio baseline / current.

Scenarios:

- ``cli-empty``: ``mixdyn run examples/antonya.yaml --out OUT`` (figures and animation) with
  an empty cache folder each time;
- ``cli-warm``: the same, the cache filled by a first run;
- ``cli-changed``: the file edited in place, one number changed (the parameter ``T``, a new
  value each time), the cache filled by a run of the file before the edit;
- ``api-second``: a Python process building the paper's mechanism with the Python API
  (``tests/fixtures``, the paper's loads) and calling ``md.forward`` on it as the file's
  forward run does, the cache filled by a first process;
- ``check``: ``mixdyn check`` of the edited copy (a new number each time) in its own process
  (``MIXDYN_SERVER=0``), the cache filled;
- ``check-served``: the same answered by a command server started before
  (``MIXDYN_SERVER=1``; a revision without one runs it in its own process);
- ``show-served``: ``mixdyn show examples/antonya.yaml -o OUT.png``, answered likewise.

Usage::

    python benchmarks/latency.py [--repeat 5] [--baseline REV] [--only cli-warm ...] [--as-is]
"""

from __future__ import annotations

import argparse
import os
import pathlib
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "antonya.yaml"
#: Targets of issue 12 [s].
TARGETS = {"cli-empty": 8.0, "cli-warm": 2.0, "cli-changed": 2.5, "api-second": 2.0}
#: Targets of issue 32 ("check and show start in well under a second warm") [s].
TARGETS.update({"check": 1.0, "check-served": 0.5, "show-served": 0.5})
SERVED = ("check-served", "show-served")
XLA_FLAGS = "--xla_cpu_enable_concurrency_optimized_scheduler=false"

API_SCRIPT = """
import sys
import numpy as np
sys.path.insert(0, {tests!r})
import mixdyn as md
from fixtures import paper_mechanism
loads = [
    md.Torque("T2", "crank", law=500.0),
    md.Torque("T3", "coupler", law=-500.0),
    md.PointForce("F1", "slider", along=(1.0, 0.0), law=md.Harmonic(10.0, np.pi / 2)),
]
model = paper_mechanism(forces=loads)
res = md.forward(model, np.linspace(0, 2, 201), hold=("crank.phi", "coupler.phi"),
                 rtol=1e-10, atol=1e-10)
assert res.q.shape == (201, model.nq)
"""


#: Python's own bytecode cache, as a user has it: on, unless ``--as-is`` keeps the caller's
#: ``PYTHONDONTWRITEBYTECODE`` (set in some sandboxes: every process then compiles mixdyn's
#: ~80 modules from source, ~0.1 s here).
KEEP_ENV = {"as_is": False}


def _env(src: pathlib.Path, cache: pathlib.Path) -> dict:
    env = dict(os.environ)
    env.pop("MIXDYN_NO_CACHE", None)
    if not KEEP_ENV["as_is"]:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["MIXDYN_CACHE_DIR"] = str(cache)
    env["XLA_FLAGS"] = env.get("XLA_FLAGS") or XLA_FLAGS
    env["PYTHONPATH"] = os.pathsep.join([str(src), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def _time(cmd: list[str], env: dict, cwd: pathlib.Path) -> float:
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True, timeout=900)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    return seconds


def _changed(tmp: pathlib.Path, k: int | None) -> pathlib.Path:
    """The designer's copy of the example, ``edited.yaml``, as it is (k None) or edited in
    place with the parameter T changed (a new value for each k)."""
    text = EXAMPLE.read_text(encoding="utf-8")
    if k is not None:
        text, n = re.subn(r"(?m)^(\s*T:\s*)500\b", rf"\g<1>{500 + k + 1}", text)
        assert n == 1, "the example's parameter T: 500 was not found"
    path = tmp / "edited.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def measure(srcs: dict[str, pathlib.Path], repeat: int, only) -> dict[str, dict[str, list]]:
    """Seconds per variant (a mixdyn ``src`` folder) and scenario, the variants taking turns
    run by run (so that a drift of the machine's speed touches them alike)."""
    py = sys.executable
    # The command as the README runs it: the environment's ``mixdyn`` script (its process is
    # the command's own, which starts the figure worker and reads the file's programs ahead;
    # ``python -m mixdyn.cli`` is not), importing each variant's mixdyn from PYTHONPATH.
    script = pathlib.Path(py).with_name("mixdyn")
    cli = [str(script), "run"] if script.exists() else [py, "-m", "mixdyn.cli", "run"]
    out = {v: {} for v in srcs}
    # A command server's socket path must stay short (about 100 bytes): a folder in /tmp.
    servers = pathlib.Path(
        tempfile.mkdtemp(prefix="mxl", dir="/tmp" if os.name == "posix" else None)
    )
    with tempfile.TemporaryDirectory(prefix="mixdyn-latency-") as tmp_:
        tmp = pathlib.Path(tmp_)
        result = tmp / "out"
        scripts = {v: tmp / f"api-{v}.py" for v in srcs}
        for v, src in srcs.items():  # each tree's own fixtures
            scripts[v].write_text(API_SCRIPT.format(tests=str(src.parent / "tests")), "utf-8")
        env = {v: _env(src, tmp / v / "cache") for v, src in srcs.items()}
        api_env = {v: _env(src, tmp / v / "api-cache") for v, src in srcs.items()}
        for v in srcs:  # fill the caches: a first run, a first process
            if {"cli-warm", "cli-changed"} & set(only):
                _time([*cli, str(EXAMPLE), "--out", str(result)], env[v], tmp)
            if "cli-changed" in only:
                _time([*cli, str(_changed(tmp, None)), "--out", str(result)], env[v], tmp)
            if "api-second" in only:
                _time([py, str(scripts[v])], api_env[v], tmp)
        own = {v: dict(env[v], MIXDYN_SERVER="0") for v in srcs}
        served = {v: dict(env[v], MIXDYN_SERVER="1", MIXDYN_SERVER_DIR=str(servers)) for v in srcs}
        if set(SERVED) & set(only):
            for v in srcs:
                _time([*cli[:-1], "check", str(_changed(tmp, None))], own[v], tmp)  # its programs
                _time([*cli[:-1], "show", str(EXAMPLE), "-o", str(tmp / "s.png")], own[v], tmp)
                start = subprocess.run(
                    [*cli[:-1], "server", "start"],
                    env=served[v],
                    cwd=tmp,
                    capture_output=True,
                    text=True,
                    timeout=300,
                )
                if start.returncode == 0:  # a revision with a command server
                    _time([*cli[:-1], "check", str(_changed(tmp, None))], served[v], tmp)
                    _time(
                        [*cli[:-1], "show", str(EXAMPLE), "-o", str(tmp / "s.png")], served[v], tmp
                    )
        for k in range(repeat):
            changed = _changed(tmp, k)
            for v, src in srcs.items():
                t = out[v]
                if "cli-empty" in only:
                    empty = tmp / v / f"empty{k}"
                    t.setdefault("cli-empty", []).append(
                        _time([*cli, str(EXAMPLE), "--out", str(result)], _env(src, empty), tmp)
                    )
                    shutil.rmtree(empty, ignore_errors=True)
                if "cli-warm" in only:
                    t.setdefault("cli-warm", []).append(
                        _time([*cli, str(EXAMPLE), "--out", str(result)], env[v], tmp)
                    )
                if "cli-changed" in only:
                    t.setdefault("cli-changed", []).append(
                        _time([*cli, str(changed), "--out", str(result)], env[v], tmp)
                    )
                if "api-second" in only:
                    t.setdefault("api-second", []).append(
                        _time([py, str(scripts[v])], api_env[v], tmp)
                    )
                for name, how in (("check", own), ("check-served", served)):
                    if name in only:
                        t.setdefault(name, []).append(
                            _time([*cli[:-1], "check", str(changed)], how[v], tmp)
                        )
                if "show-served" in only:
                    png = str(tmp / "shown.png")
                    t.setdefault("show-served", []).append(
                        _time([*cli[:-1], "show", str(EXAMPLE), "-o", png], served[v], tmp)
                    )
        for v in srcs:
            subprocess.run(
                [*cli[:-1], "server", "stop"],
                env=served[v],
                cwd=tmp,
                capture_output=True,
                timeout=120,
            )
    shutil.rmtree(servers, ignore_errors=True)
    return out


def _row(name, times, base=None) -> str:
    med = statistics.median(times)
    target = TARGETS[name]
    cells = [
        name,
        f"{med:.2f}",
        f"{min(times):.2f}",
        f"{max(times):.2f}",
        f"{target:g}",
        f"{med / target:.2f}",
    ]
    if base is not None:
        b = statistics.median(base[name])
        cells += [f"{b:.2f}", f"{b / med:.2f}"]
    return "| " + " | ".join(cells) + " |"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--repeat", type=int, default=5, help="runs per scenario (default 5)")
    ap.add_argument("--baseline", help="a git revision to compare with (e.g. a commit)")
    ap.add_argument("--only", nargs="+", choices=list(TARGETS), default=list(TARGETS))
    ap.add_argument(
        "--as-is",
        action="store_true",
        help="keep PYTHONDONTWRITEBYTECODE from the environment (default: Python's bytecode "
        "cache on, as a user has it)",
    )
    args = ap.parse_args(argv)
    KEEP_ENV["as_is"] = args.as_is
    srcs = {"current": ROOT / "src"}
    with tempfile.TemporaryDirectory(prefix="mixdyn-baseline-") as wt:
        if args.baseline:
            subprocess.run(
                ["git", "worktree", "add", "--detach", wt, args.baseline],
                cwd=ROOT,
                check=True,
                capture_output=True,
            )
            srcs["baseline"] = pathlib.Path(wt) / "src"
        try:
            times = measure(srcs, args.repeat, args.only)
        finally:
            if args.baseline:
                subprocess.run(["git", "worktree", "remove", "--force", wt], cwd=ROOT, check=False)
    current, base = times["current"], times.get("baseline")
    head = "| scenario | median [s] | min | max | target [s] | median / target |"
    rule = "|---|---|---|---|---|---|"
    if base is not None:
        head += f" baseline {args.baseline} median [s] | baseline / current |"
        rule += "---|---|"
    cache = "as in the environment" if args.as_is else "on"
    print(
        f"{args.repeat} runs per scenario, wall clock of whole processes, {os.cpu_count()} CPUs, "
        f"Python's bytecode cache {cache}"
    )
    print(head)
    print(rule)
    for name in args.only:
        print(_row(name, current[name], base))


if __name__ == "__main__":
    main()
