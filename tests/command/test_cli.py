"""The command line: every example runs from it and gives the Python API's numbers; the
paper's example writes its four figures and the animation; exit codes and one-line errors."""

import ast
import json
import os
import pathlib
import re
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
from PIL import Image
from typer.testing import CliRunner

import mixdyn as md
import mixdyn.io as mio
from fixtures import EXAMPLES, antonya_mixed
from mixdyn.cli import app, configure_cache
from mixdyn.units import engineering


@pytest.fixture(scope="module")
def cli():
    return CliRunner()


def _run(cli, *args):
    res = cli.invoke(app, [str(a) for a in args])
    assert res.exit_code == 0, res.output
    return res


# ------------------------------------------------------------------ the examples vs the API
def _api(name: str, model: md.Model) -> dict:
    """The example's runs, done with the Python API directly (not through mixdyn.io)."""
    if name == "slider_crank":
        t = np.linspace(0, np.pi, 181)
        return {"kinematics": md.kinematic(model, t), "inverse": md.inverse(model, t)}
    if name == "four_bar":
        return {
            "kinematics": md.kinematic(model, 0.05 * np.arange(126)),
            "inverse": md.inverse(model, np.linspace(0, 2 * np.pi, 126)),
        }
    if name == "pendulum":
        t = np.linspace(0, 4, 201)
        hold = ["rod.phi"]
        return {
            "swing": md.forward(model, t, rtol=1e-10, atol=1e-12, hold=hold),
            "swing_alpha": md.forward(
                model, t, method="generalized-alpha", dt=1e-3, hold=hold, rho_inf=0.9
            ),
        }
    if name == "antonya":
        t = np.linspace(0, 2, 201)
        hold = ["crank.phi", "coupler.phi"]
        fwd = md.forward(model, t, rtol=1e-10, atol=1e-10, hold=hold)
        return {"forward": fwd, "mixed": antonya_mixed(model, t, fwd, hold=hold)}
    raise AssertionError(name)


@pytest.fixture(scope="module")
def antonya(cli, tmp_path_factory):
    """``mixdyn run examples/antonya.yaml`` with figures (shared by several tests)."""
    out = tmp_path_factory.mktemp("antonya")
    res = _run(cli, "run", EXAMPLES / "antonya.yaml", "--out", out, "--parquet")
    return out, res


def _compare(out: pathlib.Path, name: str):
    model = mio.load(EXAMPLES / f"{name}.yaml")
    api = _api(name, model)
    assert sorted(p.name for p in out.iterdir()) == sorted(api)
    for run, result in api.items():
        table = md.read_table(out / run / "results.csv")
        cols = result.columns()
        assert list(table.columns) == list(cols)
        for col, values in cols.items():
            np.testing.assert_allclose(
                table[col].to_numpy(), values, rtol=1e-12, atol=1e-12, err_msg=f"{run}: {col}"
            )
        meta = json.loads((out / run / "meta.json").read_text())
        labels = {c: engineering(result.units()[c]) for c in cols}
        assert meta["units"] == labels and table.attrs["units"] == {
            c: u for c, u in labels.items() if u
        }
        head = (out / run / "results.csv").read_text().partition("\n")[0]
        assert head.startswith("t [s],") or head.startswith("t [ms],")
        assert meta["kind"] == result.kind and meta["run"] == run
        assert meta["mixdyn_version"] == md.__version__
    return api


@pytest.mark.parametrize("name", ["slider_crank", "four_bar", "pendulum"])
def test_example_runs_from_the_cli_like_the_api(cli, tmp_path, name):
    _run(cli, "run", EXAMPLES / f"{name}.yaml", "--out", tmp_path, "--no-figures")
    api = _compare(tmp_path, name)
    if name == "pendulum":  # and the physics holds: energy conserved, methods agree
        e = api["swing"]["energy.total"]
        assert np.ptp(e) < 1e-8
        np.testing.assert_allclose(
            api["swing_alpha"]["rod.phi"], api["swing"]["rod.phi"], atol=1e-4
        )
    if name == "slider_crank":  # the closed form
        th = 2 * api["kinematics"].t
        exact = 0.1 * np.cos(th) + np.sqrt(0.3**2 - (0.1 * np.sin(th)) ** 2)
        np.testing.assert_allclose(api["kinematics"]["slider.x"], exact, atol=1e-10)


def test_antonya_from_the_cli_like_the_api(antonya):
    out, _ = antonya
    api = _compare(out, "antonya")
    # the paper's round trip: the mixed run recovers F1 = 10 sin(pi t / 2) and the motion
    t = api["mixed"].t
    np.testing.assert_allclose(api["mixed"]["F1"], 10 * np.sin(np.pi * t / 2), atol=1e-6)
    np.testing.assert_allclose(api["mixed"].q, api["forward"].q, atol=1e-6)
    pq = pd.read_parquet(out / "forward" / "results.parquet")
    np.testing.assert_array_equal(pq["slider.x"].to_numpy(), api["forward"]["slider.x"])
    # the Parquet file alone says its units (issue 14): mm and mN in the paper's system
    from mixdyn.io.results import parquet_units

    units = parquet_units(out / "forward" / "results.parquet")
    assert units["slider.x"] == "mm" and units["D.Fx"] == "mN" and units["t"] == "s"


def test_antonya_writes_the_papers_figures_and_the_animation(antonya):
    out, _ = antonya
    for run, name in [
        ("forward", "fig3_slider_displacement.png"),
        ("forward", "fig4_crank_rotation.png"),
        ("forward", "fig5_slider_acceleration.png"),
        ("mixed", "fig6_recovered_F1.png"),
    ]:
        path = out / run / name
        with Image.open(path) as im:
            assert im.format == "PNG" and im.size[0] >= 600 and im.size[1] >= 350
            colors = im.convert("RGB").getcolors(maxcolors=1_000_000)
            assert len(colors) > 50  # more than a blank canvas
    with Image.open(out / "forward" / "animation.gif") as gif:
        assert gif.n_frames == 81
        assert gif.size[0] >= 400 and gif.size[1] >= 200
        gif.seek(0)
        first = np.asarray(gif.convert("RGB"))
        gif.seek(40)
        middle = np.asarray(gif.convert("RGB"))
        assert np.mean(first != middle) > 0.001  # the mechanism moves
    page = (out / "forward" / "animation.html").read_text()
    assert "<canvas" in page and '"bodies"' in page and "crank" in page
    assert "http://" not in page and "https://" not in page  # self-contained
    meta = json.loads((out / "forward" / "meta.json").read_text())
    assert "fig3_slider_displacement.png" in meta["figures"]
    assert meta["settings"]["method"] == "projection" and meta["settings"]["rtol"] == 1e-10
    assert meta["stats"]["steps"] > 0
    # The run's one-page report: its three figures and the animation inline, the energies.
    assert meta["report"] == "report.html"
    report = (out / "forward" / "report.html").read_text()
    assert report.count('src="data:image/png;base64,') == 3
    assert report.count('src="data:image/gif;base64,') == 1
    balance = re.search(r"relative to the largest range or work</td><td class=n>([^<]*)<", report)
    assert float(balance.group(1)) < 1e-6  # rtol 1e-10: energy conserved but for Wn


def test_plot_and_animate_from_written_results(cli, antonya, tmp_path):
    out, _ = antonya
    fig = tmp_path / "f.svg"
    _run(cli, "plot", out / "forward", "-c", "slider.x", "-c", "crank.phi", "-o", fig)
    assert fig.stat().st_size > 5000 and "<svg" in fig.read_text()[:500]
    res = cli.invoke(app, ["plot", str(out / "forward"), "-c", "nope"])
    assert res.exit_code == 2 and "no column 'nope'" in res.stderr
    res = cli.invoke(app, ["plot", str(out / "forward"), "-c", "slider.xx"])  # a typo
    assert res.exit_code == 2 and "did you mean 'slider.x'" in res.stderr
    assert "crank.omega" not in res.stderr  # not every column
    base = tmp_path / "anim"
    _run(
        cli,
        "animate",
        EXAMPLES / "antonya.yaml",
        "--run",
        "forward",
        "--results",
        out / "forward",
        "-o",
        base,
        "--frames",
        "12",
    )
    with Image.open(base.with_suffix(".gif")) as gif:
        assert gif.n_frames == 12
    assert base.with_suffix(".html").stat().st_size > 2000


def test_check_prints_the_mobility(cli):
    res = _run(cli, "check", EXAMPLES / "antonya.yaml")
    assert "degrees of freedom: 2" in res.stdout
    assert "run mixed (mixed)" in res.stdout and "unknown F1" in res.stdout
    assert res.stdout.strip().endswith("ok")


def test_numerical_failure_exits_1_with_time_and_cause(cli, tmp_path):
    text = (EXAMPLES / "slider_crank.yaml").read_text()
    # drive the slider beyond the reach of crank + rod (0.4 m): no configuration exists
    text = text.replace(
        "{type: coordinate, name: motor, coordinate: crank.phi, law: omega*t}",
        "{type: coordinate, name: motor, coordinate: slider.x, law: 0.35 + 0.2*t}",
    )
    text = text.replace(
        "    kind: kinematic\n", "    kind: kinematic\n    initial: {crank.phi: 1.0}\n"
    )
    path = tmp_path / "reach.yaml"
    path.write_text(text)
    res = cli.invoke(app, ["run", str(path), "--run", "kinematics", "--out", str(tmp_path)])
    assert res.exit_code == 1, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.output
    assert lines[0].startswith(f"{path}: run 'kinematics': numerical failure")
    assert "at t = " in lines[0]


def test_unknown_run_name(cli, tmp_path):
    res = cli.invoke(app, ["run", str(EXAMPLES / "pendulum.yaml"), "--run", "nope"])
    assert res.exit_code == 2
    assert "no run 'nope'" in res.stderr and "swing" in res.stderr


def test_help_on_everything(cli):
    for cmd in ([], ["check"], ["run"], ["plot"], ["animate"], ["schema"], ["dump"]):
        res = cli.invoke(app, [*cmd, "--help"])
        assert res.exit_code == 0 and "Usage" in res.stdout, cmd
    res = cli.invoke(app, ["--version"])
    assert res.stdout.strip() == f"mixdyn {md.__version__}"


def test_schema_and_dump(cli, tmp_path):
    res = _run(cli, "schema")
    schema = json.loads(res.stdout)
    assert "bodies" in schema["properties"]
    out = tmp_path / "again.yaml"
    _run(cli, "dump", EXAMPLES / "four_bar.yaml", "-o", out)
    assert mio.read(out) == mio.read(EXAMPLES / "four_bar.yaml")


@pytest.mark.parametrize("name", ["antonya.yaml", "four_bar.yaml", "antonya_sweep.yaml"])
def test_dump_keeps_the_comments(cli, tmp_path, name):
    """Every comment of the file whose line keeps a key is in the dump, in the same order;
    a default written out (``gravity: [0, 0]``, ``html: true``) goes; the dump reads back as
    the same description."""
    src = (EXAMPLES / name).read_text()
    path = tmp_path / name
    path.write_text(src)
    out = tmp_path / f"dumped_{name}"
    _run(cli, "dump", path, "-o", out)
    text = out.read_text()
    assert mio.read(out) == mio.read(path)
    assert "gravity: [0, 0]" not in text and "html: true" not in text
    comments = [
        line.split("#", 1)[1].strip()
        for line in src.splitlines()
        if "#" in line and "gravity: [0, 0]" not in line and "html: true" not in line
    ]
    kept = [line.split("#", 1)[1].strip() for line in text.splitlines() if "#" in line]
    assert len(comments) > 3 and kept == comments


def test_cache_can_be_turned_off(monkeypatch):
    monkeypatch.setenv("MIXDYN_NO_CACHE", "1")
    assert configure_cache() is None


def test_the_installed_command(tmp_path):
    """The real entry point, in its own process: a bad file gives exit 2 and one line."""
    exe = pathlib.Path(sys.executable).parent / "mixdyn"
    cmd = (
        [str(exe)]
        if exe.exists()
        else [sys.executable, "-c", "from mixdyn.cli import main; main()"]
    )
    bad = tmp_path / "bad.yaml"
    bad.write_text("bodies:\n  - name: b\n    mass: 3 mm\n")
    env = dict(os.environ, MIXDYN_NO_CACHE="1")
    proc = subprocess.run(
        [*cmd, "check", str(bad)], capture_output=True, text=True, env=env, timeout=120
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f"{bad}:3: body 'b', mass: '3 mm': 'mm' is a unit of length, expected a mass (kg); "
        "give the value in a unit of mass"
    ]
    assert proc.stdout == ""


@pytest.mark.parametrize(("code", "rc", "err"), [(3, 3, ""), (None, 0, ""), ("stop", 1, "stop\n")])
def test_the_command_leaves_as_python_would(code, rc, err):
    """``mixdyn.cli._leave`` skips the interpreter's teardown, not what a normal exit does:
    a thread that is not a daemon finishes, ``atexit`` functions run after it, buffered
    output is written (to a pipe: block-buffered), the code reads as ``SystemExit``'s."""
    script = (
        "import atexit, threading, time\n"
        "from mixdyn.cli import _leave\n"
        "atexit.register(lambda: print('atexit'))\n"
        "threading.Thread(target=lambda: (time.sleep(0.3), print('thread'))).start()\n"
        "print('buffered', end=' ')\n"
        f"_leave({code!r})\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == rc
    assert proc.stdout == "buffered thread\natexit\n"
    assert proc.stderr == err


@pytest.mark.parametrize(
    ("words", "file", "runs"),
    [
        (["m.yaml"], "m.yaml", []),
        (["m.yaml", "--out", "o", "--no-figures"], "m.yaml", []),
        (["-o", "o", "m.yaml", "--parquet", "-r", "forward"], "m.yaml", ["forward"]),
        (["--run=mixed", "m.yaml", "--run", "forward", "--out=x"], "m.yaml", ["mixed", "forward"]),
        (["m.yaml", "n.yaml"], None, None),  # two files: not a plain command line
        (["m.yaml", "-rforward"], None, None),  # an option written otherwise
        (["m.yaml", "--out"], None, None),  # a value missing
        (["--help"], None, None),
    ],
)
def test_the_early_job_tag_is_the_one_run_uses(words, file, runs):
    """``mixdyn run`` starts reading its programs when mixdyn is imported, under the tag it
    reads from the command line (``_command.job_tag``): the tag ``run`` itself uses, or None
    where the command line is not plain (``run`` then reads them itself)."""
    from mixdyn.runtime import _command

    tag = _command.job_tag(["/usr/bin/mixdyn", "run", *words])
    assert tag == (None if file is None else _command.run_tag(file, runs))
    assert _command.job_tag(["python", "run", *words]) is None
    assert _command.job_tag(["/usr/bin/mixdyn", "check", *words]) is None


@pytest.mark.parametrize("argv0", ["/usr/bin/mixdyn", "-c"])
def test_only_the_command_paces_the_collector(argv0):
    """Importing mixdyn in the ``mixdyn`` command raises the garbage collector's thresholds
    (``_command.GC_THRESHOLDS``); in any other program they stay as they were."""
    script = (
        "import gc, sys\n"
        f"sys.argv = [{argv0!r}, 'check']\n"
        "before = gc.get_threshold()\n"
        "import mixdyn\n"
        "from mixdyn.runtime import _command\n"
        "print(repr([before, gc.get_threshold(), _command.GC_THRESHOLDS]))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120
    )
    before, after, paced = ast.literal_eval(proc.stdout)
    assert after == (paced if argv0.endswith("mixdyn") else before)
    assert before != paced


def _processes_with(token: str) -> list[int]:
    """Processes whose environment holds ``token`` (Linux: ``/proc``)."""
    found = []
    for entry in pathlib.Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if token.encode() in (entry / "environ").read_bytes():
                    found.append(int(entry.name))
            except OSError:
                pass
    return found


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_the_early_figure_worker_ends_with_the_command(tmp_path):
    """``mixdyn run`` starts its figure worker before importing JAX (mixdyn.runtime._command); a run
    that stops on an input error before it draws leaves no worker behind, and a command
    line that draws nothing starts none."""
    import uuid

    from mixdyn.runtime import _command

    exe = pathlib.Path(sys.executable).parent / "mixdyn"
    if not exe.exists():
        pytest.skip("the mixdyn command is not installed beside this Python")
    assert _command.draws(["/x/mixdyn", "run", "m.yaml"])
    assert _command.draws(["mixdyn", "run", "m.yaml", "--out", "o"])
    assert not _command.draws(["mixdyn", "run", "m.yaml", "--no-figures"])
    assert not _command.draws(["mixdyn", "run", "--help"])
    assert not _command.draws(["mixdyn", "check", "m.yaml"])
    assert not _command.draws(["python", "run", "m.yaml"])
    bad = tmp_path / "bad.yaml"
    bad.write_text("bodies:\n  - name: b\n    mass: 3 mm\n")
    token = f"MIXDYN_TEST_TOKEN={uuid.uuid4().hex}"
    env = dict(os.environ, MIXDYN_NO_CACHE="1", MIXDYN_TEST_TOKEN=token.split("=")[1])
    for extra, says in (([], "'mm' is a unit of length"), (["--bogus"], "--bogus")):
        # the file's error: the painter took the worker and stops it; an unknown option:
        # the command ends before any painter (the worker nobody took is stopped at exit,
        # or ends at the end of its input)
        proc = subprocess.run(
            [str(exe), "run", str(bad), "--out", str(tmp_path / "o"), *extra],
            capture_output=True,
            text=True,
            env=env,
            timeout=120,
        )
        assert proc.returncode == 2 and says in proc.stderr
        time.sleep(0.2)
        assert _processes_with(token) == []


def _environ_of(pid: int) -> list[bytes]:
    """``/proc/PID/environ``'s entries, read again while it is empty: the kernel shows an
    empty environment for a moment after ``exec`` (the new program's stack not yet laid out),
    which is when ``Popen`` returns."""
    path = pathlib.Path(f"/proc/{pid}/environ")
    for _ in range(200):
        entries = [e for e in path.read_bytes().split(b"\0") if e]
        if entries:
            return entries
        time.sleep(0.01)
    return []


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("user", [None, "2"])
def test_the_figure_worker_runs_blas_on_one_thread_unless_told(monkeypatch, user):
    """The figure worker's environment (``/proc/PID/environ``, read from outside) names one
    OpenBLAS thread, or the number the user set."""
    from mixdyn.runtime import _command

    if user is None:
        monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    else:
        monkeypatch.setenv("OPENBLAS_NUM_THREADS", user)
    proc, second = _command.spawn()
    if proc is None:
        pytest.skip("no worker process here")
    try:
        environ = _environ_of(proc.pid)
    finally:
        _command.stop(proc)
        for fd in second or ():
            os.close(fd)
    assert f"OPENBLAS_NUM_THREADS={user or 1}".encode() in environ
