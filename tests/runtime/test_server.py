"""The command server (:mod:`mixdyn.runtime._server`): a command it answers reads and writes
what the command's own process would, in the client's folder, environment and streams, and
ends with the same exit code; a server is used only for the installation and settings it
was started with."""

import os
import pathlib
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time

import pytest

from fixtures.files import CRANK_FILE
from mixdyn import cli
from mixdyn.runtime import _server

BAD_FILE = "bodies:\n  - name: b\n    mass: 3 mm\n"


def _own(capfd, args, cwd):
    """The command run in this process as ``mixdyn`` runs it, from ``cwd``: (code, stdout,
    stderr)."""
    here = os.getcwd()
    os.chdir(cwd)
    try:
        capfd.readouterr()
        code = cli.command(args)
        sys.stdout.flush()
        out, err = capfd.readouterr()
    finally:
        os.chdir(here)
    return code, out, err


def _served(args, cwd, env, tmp_path):
    """The command sent from ``cwd`` over a socket to :func:`_server._answer` (a thread of
    this process standing for the server, whose own folder is another), with files for its
    stdin, stdout and stderr: (code, stdout, stderr)."""
    client, server = socket.socketpair()
    names = [tmp_path / f"fd{i}" for i in range(3)]
    names[0].write_text("")
    files = [open(names[0]), open(names[1], "w"), open(names[2], "w")]  # noqa: SIM115
    answered = []
    thread = threading.Thread(target=lambda: answered.append(_server._answer(server, cli.command)))
    try:
        thread.start()
        code = _server._ask(
            client, ["mixdyn", *args], env, fds=[f.fileno() for f in files], cwd=cwd
        )
        thread.join(60)
    finally:
        client.close()
        server.close()
        for f in files:
            f.close()
    assert answered == [True]
    return code, names[1].read_text(), names[2].read_text()


def test_a_served_command_is_the_command_run_in_its_own_process(tmp_path, capfd):
    """``check`` of a good and of a bad file named relative to the client's folder: the
    same output, error line and exit code as in the command's own process; the server's
    folder, environment and streams are its own again afterwards."""
    model = tmp_path / "model"
    model.mkdir()
    (model / "crank.yaml").write_text(CRANK_FILE)
    (model / "bad.yaml").write_text(BAD_FILE)
    env = dict(os.environ, MIXDYN_SERVED_TEST="1")
    before = (os.getcwd(), dict(os.environ), sys.stdout, sys.stderr)
    for name, rc in (("crank.yaml", 0), ("bad.yaml", 2)):
        own = _own(capfd, ["check", name], model)
        served = _served(["check", name], model, env, tmp_path)
        assert own[0] == rc
        assert served == own
    assert (os.getcwd(), dict(os.environ), sys.stdout, sys.stderr) == before


def test_a_server_is_keyed_by_the_settings_read_at_import():
    """Settings read at import (mixdyn's, JAX's, Python's) give another server; the
    server's own switch and unrelated variables do not."""
    base = {"HOME": "/h", "MIXDYN_NO_CACHE": "1"}
    key = _server.key(base)
    assert _server.key(dict(base)) == key
    assert _server.key({**base, "MIXDYN_SERVER": "1", "EDITOR": "vi"}) == key
    for name, value in (("MIXDYN_NO_CACHE", "0"), ("JAX_PLATFORMS", "cpu"), ("PYTHONPATH", "/x")):
        assert _server.key({**base, name: value}) != key
    assert _server.policy({"MIXDYN_SERVER": "0"}) == "off"
    assert _server.policy({"MIXDYN_SERVER": "1"}) == "start"


def _mixdyn(args, env, cwd=None):
    exe = pathlib.Path(sys.executable).with_name("mixdyn")
    cmd = (
        [str(exe)]
        if exe.exists()
        else [sys.executable, "-c", "from mixdyn.cli import main; main()"]
    )
    proc = subprocess.run(
        [*cmd, *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=300
    )
    return proc.returncode, proc.stdout, proc.stderr


@pytest.mark.slow  # long: run by CI's slow set
def test_the_command_starts_a_server_and_is_answered_by_it(tmp_path):
    """With ``MIXDYN_SERVER=1`` the first ``check`` runs in its own process and starts a
    server; the next commands are answered by it (its log says so) with the output, files
    and exit codes of the command's own process, also after the file changed; ``mixdyn
    server stop`` stops it."""
    folder = pathlib.Path(tempfile.mkdtemp(prefix="mxs", dir="/tmp"))  # a short socket path
    env = dict(os.environ, MIXDYN_SERVER_DIR=str(folder), MIXDYN_SERVER="1")
    own_env = dict(env, MIXDYN_SERVER="0")
    model = tmp_path / "crank.yaml"
    model.write_text(CRANK_FILE)
    try:
        own = _mixdyn(["check", str(model)], own_env)
        assert own[0] == 0
        assert _mixdyn(["check", str(model)], env) == own  # starts the server
        deadline = time.monotonic() + 120
        while not list(folder.glob("*.sock")) and time.monotonic() < deadline:
            time.sleep(0.2)
        (sock,) = folder.glob("*.sock")
        log = sock.with_suffix(".log")
        assert _mixdyn(["check", "crank.yaml"], env, cwd=tmp_path) == _mixdyn(
            ["check", "crank.yaml"], own_env, cwd=tmp_path
        )
        model.write_text(BAD_FILE)
        bad = _mixdyn(["check", str(model)], env)
        assert bad[0] == 2
        assert bad == _mixdyn(["check", str(model)], own_env)
        model.write_text(CRANK_FILE)
        shown = _mixdyn(["show", str(model), "-o", str(tmp_path / "served.png")], env)
        assert shown[0] == 0
        assert _mixdyn(["show", str(model), "-o", str(tmp_path / "own.png")], own_env)[0] == 0
        assert (tmp_path / "served.png").read_bytes() == (tmp_path / "own.png").read_bytes()
        lines = log.read_text().splitlines()
        assert lines[0].split()[2:4] == ["ready", "in"]
        answered = [line.split()[2:5] for line in lines[1:]]
        assert answered == [
            ["check:", "exit", "0"],
            ["check:", "exit", "2"],
            ["show:", "exit", "0"],
        ]
        assert _mixdyn(["server", "stop"], env)[1].strip() == "stopped the command server"
        assert not sock.exists()
    finally:
        _mixdyn(["server", "stop"], env)
        shutil.rmtree(folder, ignore_errors=True)
