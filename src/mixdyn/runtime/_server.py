"""The command server: ``mixdyn check``, ``show``, ``plot`` and ``schema`` answered by a process
that has mixdyn imported already.

A ``mixdyn`` process spends ~0.8 s importing JAX and mixdyn before a command starts, more than
``check`` itself needs for a model it has seen (~0.05 s). The server is a process of the
same interpreter, installation and settings that has done that once and answers those
commands one after another: the command's process (the *client*) hands it its command line,
working folder, environment and its standard streams themselves (their file descriptors,
over a Unix socket), so that the command reads and writes the user's terminal, pipes and
files as it would have itself, and ends with the exit code the server sends back.

*Which server:* one per :func:`key`: the interpreter, mixdyn's source files (their sizes and
times), the installed packages (their folders' times) and the environment variables read
at import (:data:`KEYED_PREFIXES`). A changed installation, source file or setting is a
different key, so a server never answers for other code; an unused one stops after
:data:`IDLE_SECONDS`. Its socket lives in :func:`folder`, readable by its user only.

*When:* ``MIXDYN_SERVER`` decides (:func:`policy`): ``0`` never, ``1`` start one when none
runs; unset, a command started from a terminal (stdin and stdout) starts one, any other uses
one that runs and starts none. The command that starts a server runs itself, in its own
process, as always; the server is ready ~2 s later. ``mixdyn server stop`` stops it.

*Failures:* where no server answers, or it declines before the command starts, the command
runs in its own process (nothing is lost but time). A server that ends while running a
command is a failure of that command (exit 1, one line saying so).

This module imports nothing from mixdyn, nor JAX: the client side runs before them.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import pathlib
import signal
import socket
import struct
import subprocess
import sys
import time

#: The commands a server answers.
SERVED = frozenset({"check", "show", "plot", "schema"})

#: Seconds a server waits for a command before it stops.
IDLE_SECONDS = 600.0

#: Commands a server answers before it stops (its other state only grows; its compiled
#: programs are given back where they crowd the memory mappings: :func:`_release_if_crowded`).
MAX_COMMANDS = 1000

#: Environment variables that decide what a process is once it has imported mixdyn (read at
#: import: JAX's and XLA's settings, mixdyn's cache, Python's path and encoding, the BLAS
#: threads, matplotlib's configuration, the locale): part of the :func:`key`.
KEYED_PREFIXES = ("MIXDYN_", "JAX_", "XLA_", "PYTHON", "MPL", "OPENBLAS_", "OMP_", "LANG", "LC_")

#: Seconds a client waits for a server to accept its connection.
CONNECT_SECONDS = 1.0

#: Seconds a client leaves a server it started to get ready before it starts another.
STARTING_SECONDS = 60.0

#: The longest socket path a Unix socket takes everywhere (108 bytes on Linux, 104 on macOS).
MAX_PATH_BYTES = 103

_ACCEPTED, _EXITED, _DECLINED = b"A", b"X", b"D"
_PACKAGE = pathlib.Path(__file__).resolve().parent.parent


def policy(environ=os.environ) -> str:
    """``"off"``, ``"start"`` (start a server when none runs) or ``"use"`` (use one that
    runs): ``MIXDYN_SERVER`` if set (``0``/``1``), else ``"start"`` from a terminal."""
    value = environ.get("MIXDYN_SERVER", "").strip().lower()
    if value in ("0", "off", "no", "false"):
        return "off"
    if value in ("1", "on", "yes", "true"):
        return "start"
    try:
        interactive = os.isatty(0) and os.isatty(1)
    except OSError:
        interactive = False
    return "start" if interactive else "use"


def folder(environ=os.environ) -> pathlib.Path:
    """The servers' folder: ``$MIXDYN_SERVER_DIR``, else ``$XDG_RUNTIME_DIR/mixdyn``, else
    ``~/.cache/mixdyn/server``."""
    if environ.get("MIXDYN_SERVER_DIR"):
        return pathlib.Path(environ["MIXDYN_SERVER_DIR"])
    if environ.get("XDG_RUNTIME_DIR"):
        return pathlib.Path(environ["XDG_RUNTIME_DIR"], "mixdyn")
    return pathlib.Path.home() / ".cache" / "mixdyn" / "server"


def key(environ=os.environ) -> str:
    """What a server is (see the module's docstring), as 24 hexadecimal digits."""
    h = hashlib.sha256()
    h.update(f"{sys.executable}\n{sys.version}\n{_PACKAGE}\n".encode())
    for entry in sorted(_source_files(), key=lambda e: e.path):
        st = entry.stat()
        h.update(f"{entry.path}:{st.st_size}:{st.st_mtime_ns}\n".encode())
    for entry in sys.path:
        if entry.endswith(("site-packages", "dist-packages")):
            with contextlib.suppress(OSError):
                h.update(f"{entry}:{os.stat(entry).st_mtime_ns}\n".encode())
    for name in sorted(environ):
        if name.startswith(KEYED_PREFIXES) and not name.startswith("MIXDYN_SERVER"):
            h.update(f"{name}={environ[name]}\n".encode())
    return h.hexdigest()[:24]


def _source_files(root: pathlib.Path = _PACKAGE):
    """mixdyn's source files: ``os.DirEntry`` of every ``.py`` under the package."""
    with os.scandir(root) as entries:
        for entry in entries:
            if entry.is_dir(follow_symlinks=False) and entry.name != "__pycache__":
                yield from _source_files(pathlib.Path(entry.path))
            elif entry.name.endswith(".py"):
                yield entry


def address(environ=os.environ) -> pathlib.Path:
    """The socket of the server for this process's :func:`key`."""
    return folder(environ) / f"{key(environ)}.sock"


def _own_folder(path: pathlib.Path) -> bool:
    """Make ``path`` (mode 0700) if needed; whether it is a folder of this user that no one
    else may enter (a server's socket is used only there)."""
    with contextlib.suppress(FileExistsError, OSError):
        path.mkdir(mode=0o700, parents=True)
    try:
        st = path.stat()
    except OSError:
        return False
    return path.is_dir() and st.st_uid == os.getuid() and not st.st_mode & 0o077


# --------------------------------------------------------------------------- the client
def forward(argv: list[str], environ=os.environ) -> int | None:
    """Have a server run the command line ``argv`` (``mixdyn COMMAND ...``) on this process's
    standard streams: its exit code, or None where no server ran it (the caller then runs
    it). Where none runs and :func:`policy` says so, one is started for the next command."""
    if len(argv) < 2 or argv[1] not in SERVED or not hasattr(socket, "AF_UNIX"):
        return None
    how = policy(environ)
    if how == "off" or not _own_folder(folder(environ)):
        return None
    path = address(environ)
    if len(os.fsencode(path)) > MAX_PATH_BYTES:
        return None  # no socket there (MIXDYN_SERVER_DIR: a shorter folder)
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        sock.settimeout(CONNECT_SECONDS)
        sock.connect(str(path))
    except OSError:
        sock.close()
        if how == "start":
            start(path, environ)
        return None
    with sock:
        return _ask(sock, argv, environ)


def _ask(sock: socket.socket, argv: list[str], environ, fds=(0, 1, 2), cwd=None) -> int | None:
    """Send the command to a connected server and wait for its end (see :func:`forward`);
    ``fds``: the command's stdin, stdout and stderr; ``cwd``: its folder (this process's)."""
    request = {
        "argv": list(argv),
        "cwd": str(cwd or os.getcwd()),
        "env": dict(environ),
        "streams": [
            [
                getattr(s, "encoding", None),
                getattr(s, "errors", None),
                bool(getattr(s, "write_through", False)),
            ]
            for s in (sys.stdin, sys.stdout, sys.stderr)
        ],
    }
    payload = json.dumps(request).encode()
    try:
        sock.settimeout(None)
        socket.send_fds(sock, [struct.pack("!Q", len(payload))], list(fds))
        sock.sendall(payload)
        first = _read(sock, 5)
    except OSError:
        return None  # not started: run here
    if len(first) < 5 or first[:1] != _ACCEPTED:
        return None  # declined (stopping, busy elsewhere): run here
    (pid,) = struct.unpack("!i", first[1:])
    try:
        end = _read(sock, 5)
    except KeyboardInterrupt:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGINT)  # the command stops as it would at Ctrl-C
        end = b""
        with contextlib.suppress(OSError, KeyboardInterrupt):
            end = _read(sock, 5)
        if len(end) < 5 or end[:1] != _EXITED:
            return 130  # what a shell gives for a command stopped by Ctrl-C
    except OSError:
        end = b""
    if len(end) < 5 or end[:1] != _EXITED:
        sys.stderr.write(
            "mixdyn: the command server stopped while running the command; run it again "
            "(MIXDYN_SERVER=0 runs it in its own process)\n"
        )
        return 1
    return struct.unpack("!i", end[1:])[0]


def _read(sock: socket.socket, n: int) -> bytes:
    """Up to ``n`` bytes: fewer only where the other side closed."""
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            break
        data += chunk
    return data


def start(path: pathlib.Path, environ=os.environ) -> bool:
    """Start a server for ``path`` in the background (its own session, no terminal), unless
    one started less than :data:`STARTING_SECONDS` ago is still getting ready. Whether one
    was started."""
    if len(os.fsencode(path)) > MAX_PATH_BYTES:
        return False
    starting = path.with_suffix(".starting")
    with contextlib.suppress(OSError):
        if time.time() - starting.stat().st_mtime < STARTING_SECONDS:
            return False
    try:
        starting.write_text(str(os.getpid()))
        log = open(path.with_suffix(".log"), "ab")  # noqa: SIM115 (the server's own)
    except OSError:
        return False
    env = {k: v for k, v in environ.items() if not k.startswith("MIXDYN_SERVER_")}
    env.pop("MIXDYN_SERVER", None)
    if environ.get("MIXDYN_SERVER_DIR"):
        env["MIXDYN_SERVER_DIR"] = environ["MIXDYN_SERVER_DIR"]
    try:
        subprocess.Popen(
            [sys.executable, "-c", "import sys, mixdyn.cli as c; c.serve(sys.argv[1])", str(path)],
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=log,
            start_new_session=True,
            env=env,
            cwd=str(path.parent),
        )
    except OSError:
        return False
    finally:
        log.close()
    return True


def stop(environ=os.environ) -> bool:
    """Stop the server for this process's :func:`key`; whether one was running."""
    path = address(environ)
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    with sock:
        try:
            sock.settimeout(CONNECT_SECONDS)
            sock.connect(str(path))
            payload = json.dumps({"stop": True}).encode()
            sock.sendall(struct.pack("!Q", len(payload)) + payload)
            sock.settimeout(30.0)
            _read(sock, 1)
        except OSError:
            return False
    return True


def running(environ=os.environ) -> bool:
    """Whether a server for this process's :func:`key` accepts commands."""
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    with sock:
        try:
            sock.settimeout(CONNECT_SECONDS)
            sock.connect(str(address(environ)))
        except OSError:
            return False
    return True


# --------------------------------------------------------------------------- the server
def serve(path: pathlib.Path, command, idle: float = IDLE_SECONDS) -> None:
    """Listen at ``path`` and answer commands one at a time with ``command`` (a function of
    the words after ``mixdyn``, giving the exit code: :func:`mixdyn.cli.command`) until
    ``idle`` seconds pass without one, :data:`MAX_COMMANDS` are answered or a stop is asked
    for. Returns at once where another server listens at ``path``."""
    t0 = time.perf_counter()
    _warm(command)
    listener = _listen(path)
    print(
        f"{time.strftime('%Y-%m-%d %H:%M:%S')} ready in {time.perf_counter() - t0:.1f} s",
        flush=True,
    )
    with contextlib.suppress(OSError):
        path.with_suffix(".starting").unlink()
    if listener is None:
        return
    inode = os.stat(path).st_ino
    try:
        listener.settimeout(idle)
        for _ in range(MAX_COMMANDS):
            try:
                conn, _ = listener.accept()
            except TimeoutError:
                break
            except KeyboardInterrupt:  # a client's Ctrl-C that came late
                continue
            with conn:
                try:
                    if not _answer(conn, command):
                        break
                except KeyboardInterrupt:  # a client's Ctrl-C after its command ended
                    continue
    finally:
        listener.close()
        with contextlib.suppress(OSError):
            if os.stat(path).st_ino == inode:
                path.unlink()


def _listen(path: pathlib.Path) -> socket.socket | None:
    """A socket listening at ``path`` (mode 0600), or None where a live server has it."""
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    for _ in range(2):
        try:
            listener.bind(str(path))
        except OSError:
            probe = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            with probe:
                try:
                    probe.connect(str(path))
                except OSError:
                    with contextlib.suppress(OSError):
                        path.unlink()  # a stopped server's socket
                    continue
            break  # another server answers there
        else:
            os.chmod(path, 0o600)
            listener.listen(16)
            return listener
    listener.close()
    return None


def _warm(command) -> None:
    """Run ``check`` and ``show`` once on a small model, output discarded: the first command
    of a process pays for imports and first traces that every command needs."""
    import tempfile

    text = (
        "mixdyn: 1\nname: warm\nunits: {length: mm, mass: kg, time: s}\n"
        "gravity: [0, -9810]\nbodies:\n  - name: rod\n    mass: 1 kg\n"
        "    inertia: 1e-3 kg*m**2\n    q0: [0, -100, 0]\n    points: {pivot: [0, 100 mm]}\n"
        "joints:\n  - {type: revolute, name: pivot, point_i: ground, point_j: rod.pivot}\n"
        "runs:\n  - {name: swing, kind: forward, time: {span: [0, 1 s], n: 11}}\n"
    )
    with tempfile.TemporaryDirectory() as tmp:
        model = pathlib.Path(tmp, "warm.yaml")
        model.write_text(text)
        with (
            open(os.devnull, "w") as sink,
            contextlib.redirect_stdout(sink),
            contextlib.redirect_stderr(sink),
        ):
            for args in (["check", str(model)], ["show", str(model)]):
                try:
                    command(args)
                except Exception as e:  # the command meets it again, and reports it
                    print(f"warming up with {args[0]}: {e!r}", file=sys.__stdout__, flush=True)


def _answer(conn: socket.socket, command) -> bool:
    """Answer one connection; False where the server should stop."""
    try:
        head, fds, _, _ = socket.recv_fds(conn, 8, 3)
    except OSError:
        return True
    try:
        if len(head) < 8:
            return True
        (n,) = struct.unpack("!Q", head)
        request = json.loads(_read(conn, n))
        if request.get("stop"):
            conn.sendall(_EXITED)
            return False
        if len(fds) != 3:
            conn.sendall(_DECLINED)
            return True
        conn.sendall(_ACCEPTED + struct.pack("!i", os.getpid()))
        t0 = time.perf_counter()
        code = _run(request, fds, command)
        with contextlib.suppress(OSError):
            conn.sendall(_EXITED + struct.pack("!i", code))
        _release_if_crowded()
        print(  # the server's log
            f"{time.strftime('%Y-%m-%d %H:%M:%S')} {' '.join(request['argv'][1:2])}: "
            f"exit {code} in {time.perf_counter() - t0:.3f} s",
            flush=True,
        )
        return True
    except (OSError, ValueError):
        return True
    finally:
        for fd in fds:
            os.close(fd)


def _release_if_crowded() -> bool:
    """After a command (its client answered): the server's compiled programs given back
    where they hold more than half the memory mappings the system allows a process
    (:func:`mixdyn.runtime._programs.release_if_crowded`; at the limit XLA crashes), so
    that a server answering many models' commands does not reach it."""
    if "mixdyn.runtime._programs" not in sys.modules:  # nothing compiled by mixdyn
        return False
    return sys.modules["mixdyn.runtime._programs"].release_if_crowded()


def _run(request: dict, fds: list[int], command) -> int:
    """Run the request's command line on its streams, folder and environment; its exit
    code. Everything borrowed is given back, whatever the command does."""
    import traceback
    import warnings

    saved_fds = [os.dup(i) for i in range(3)]
    saved_streams = (sys.stdin, sys.stdout, sys.stderr)
    saved_env, saved_cwd, saved_argv = dict(os.environ), os.getcwd(), sys.argv
    code = 1
    try:
        for i, fd in enumerate(fds):
            os.dup2(fd, i)
        os.environ.clear()
        os.environ.update(request["env"])
        os.chdir(request["cwd"])
        sys.argv = list(request["argv"])
        sys.stdin, sys.stdout, sys.stderr = _streams(request.get("streams"))
        with warnings.catch_warnings():
            try:
                code = command(sys.argv[1:])
            except KeyboardInterrupt:
                sys.stderr.write("\nAborted!\n")
                code = 130
            except Exception:
                traceback.print_exc()
                code = 1
    finally:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        sys.stdin, sys.stdout, sys.stderr = saved_streams
        for i, fd in enumerate(saved_fds):
            os.dup2(fd, i)
            os.close(fd)
        os.environ.clear()
        os.environ.update(saved_env)
        os.chdir(saved_cwd)
        sys.argv = saved_argv
    return code


def _streams(kinds) -> tuple:
    """New text streams on file descriptors 0, 1 and 2 (the client's), with the client's
    encodings, and buffered as Python buffers a process's standard streams (a terminal's and
    stderr by line, all written through where the client's were: ``PYTHONUNBUFFERED``)."""
    kinds = kinds or [[None, None, False]] * 3
    out = []
    for fd, (encoding, errors, write_through) in enumerate(kinds):
        stream = open(  # noqa: SIM115 (a standard stream, closed with the request)
            fd,
            "r" if fd == 0 else "w",
            encoding=encoding or "utf-8",
            errors=errors or "strict",
            closefd=False,
        )
        if fd:
            stream.reconfigure(line_buffering=os.isatty(fd) or fd == 2, write_through=write_through)
        out.append(stream)
    return tuple(out)
