"""Every private part of another library that mixdyn uses, each behind a version check.

mixdyn runs on the public APIs of JAX, diffrax and CPython. A few private hooks measurably
shorten the command's runs (tracing, compiling and leaving); each is used only on the
versions of the library it was checked on (:data:`KNOWN`) and only while
``$MIXDYN_PUBLIC_ONLY`` is unset. Otherwise its public fallback runs, which computes the
same results (tested both ways).

A hook is kept only while it saves at least 5% of the run it acts on, measured with
``$MIXDYN_PUBLIC_ONLY=<hook>`` against all hooks on (``benchmarks/RESULTS.md``): the
quick exit and the GIF palette act on every run of the command, the floor and the roomy
frames on a run that traces (an empty cache; a warm run loads stored programs and traces
nothing).

===================  ===============================================  ====================
hook                 private part                                     public fallback
===================  ===============================================  ====================
diffrax's floor      ``diffrax._integrate.eqxi``, swapped while       diffrax as it is
                     mixdyn traces one of its own solves and
                     restored after (:func:`chained_floor`)
roomy frames         CPython's frame-stack chunks (a code object's    a plain call
                     ``co_stacksize``; :func:`roomy`), in the
                     ``mixdyn`` command's process only
quick exit           ``atexit._run_exitfuncs`` then ``os._exit``      ``SystemExit``
                     (:func:`exit_now`), the command's process only
shared palette       Pillow's ``GifImagePlugin._get_optimize``,       Pillow as it is
                     swapped while a GIF of frames sharing one
                     palette is written (:func:`shared_palette`),
                     in the command's figure worker only
test scheduling      pytest-xdist's ``_split_scope``                  xdist's own
                     (:func:`whole_module_scheduler`), mixdyn's       scheduling
                     test session only
===================  ===============================================  ====================

Nothing here changes another library for code outside mixdyn's own calls: the swap of
diffrax's global lasts as long as mixdyn traces a solve, and what it swaps in returns the
same bits (see :mod:`mixdyn.runtime._clip_floor`).
"""

from __future__ import annotations

import contextlib
import functools
import importlib.metadata
import os
import re
import sys
import threading
from collections.abc import Callable

#: The environment variable that turns every private hook off (``1``).
PUBLIC_ONLY_ENV = "MIXDYN_PUBLIC_ONLY"

#: Versions each hook was checked on: distribution -> (first, first not checked). A version
#: outside the range takes the public path.
KNOWN = {
    "diffrax": ((0, 6), (0, 8)),  # checked: 0.7.2
    "python": ((3, 11), (3, 14)),  # CPython 3.11-3.13: frames in chunks of 16 KiB
    "pytest-xdist": ((3, 5), (3, 9)),  # checked: 3.8.0 (mixdyn's test session only)
    "pillow": ((13, 0), (13, 1)),  # checked: 13.0.0 (the command's figure worker only)
}


def version(distribution: str) -> tuple[int, ...] | None:
    """The installed version of ``distribution`` as numbers (``"python"``: the interpreter's;
    None where it is not installed)."""
    if distribution == "python":
        return tuple(sys.version_info[:3]) if sys.implementation.name == "cpython" else None
    try:
        text = importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return None
    return tuple(int(x) for x in re.findall(r"\d+", text)[:3])


#: The hooks by name, as ``$MIXDYN_PUBLIC_ONLY`` may list them.
HOOKS = (
    "chained_floor",
    "roomy",
    "exit_now",
    "shared_palette",
    "whole_module_scheduler",
)


def public_only(hook: str | None = None) -> bool:
    """Whether ``$MIXDYN_PUBLIC_ONLY`` sends ``hook`` (None: every hook) to its public path:
    ``1`` names every hook; a comma-separated list of names from :data:`HOOKS` names those
    (to measure what each hook gives); unset, empty or ``0`` names none."""
    text = os.environ.get(PUBLIC_ONLY_ENV, "").strip()
    if text in ("", "0"):
        return False
    names = {name.strip() for name in text.split(",")}
    if not names & set(HOOKS):
        return True
    return hook is not None and hook in names


def allowed(
    distribution: str, installed: tuple[int, ...] | None = None, hook: str | None = None
) -> bool:
    """Whether the private hook ``hook`` into ``distribution`` runs: its version (default:
    the installed one) is in :data:`KNOWN` and ``$MIXDYN_PUBLIC_ONLY`` does not name it."""
    if public_only(hook):
        return False
    installed = version(distribution) if installed is None else installed
    first, after = KNOWN[distribution]
    return installed is not None and first <= installed < after


# --------------------------------------------------------------------------- diffrax
_floor_lock = threading.Lock()
_floor = {"depth": 0, "saved": None}


@contextlib.contextmanager
def chained_floor():
    """A context for tracing one of mixdyn's ``diffrax.diffeqsolve`` calls in which diffrax
    computes its end-of-interval floor as one loop instead of 100 copies of ``nextafter``
    (:mod:`mixdyn.runtime._clip_floor`): the same bits, ~25% less to trace, compile and
    load for a projection integrator. diffrax's module global is restored when the last
    such context (of any thread) ends. Public fallback: diffrax as it is."""
    if not allowed("diffrax", hook="chained_floor"):
        yield
        return
    with _floor_lock:
        if _floor["depth"] == 0:
            _floor["saved"] = _swap_floor()
        _floor["depth"] += 1
    try:
        yield
    finally:
        with _floor_lock:
            _floor["depth"] -= 1
            if _floor["depth"] == 0 and _floor["saved"] is not None:
                from diffrax import _integrate

                _integrate.eqxi = _floor["saved"]
                _floor["saved"] = None


def _swap_floor():
    """Give ``diffrax._integrate`` the chained floor; returns what it had (None where this
    diffrax has no such global: nothing changed)."""
    try:
        from diffrax import _integrate
    except ImportError:  # pragma: no cover - a diffrax laid out otherwise
        return None
    from ._clip_floor import Internal

    internal = getattr(_integrate, "eqxi", None)
    if internal is None or not hasattr(internal, "prevbefore") or isinstance(internal, Internal):
        return None
    _integrate.eqxi = Internal(internal)
    return internal


# --------------------------------------------------------------------------- CPython
#: Operand-stack slots given to :func:`roomy`'s frame: 33,000 x 8 bytes (264 KB) does not
#: fit in a 16 KiB chunk nor in 256 KiB, so its chunk is 512 KiB, ~248 KiB of it left for
#: the calls made from it.
SLOTS = 33_000

_roomy_on = {"on": False}


def _plain(fn: Callable, *args, **kwargs):
    return fn(*args, **kwargs)


def _roomy(fn: Callable, *args, **kwargs):
    return fn(*args, **kwargs)


@functools.cache
def _roomy_code() -> bool:
    """Give :func:`_roomy` its over-sized operand stack (once); False where not allowed."""
    if not allowed("python", hook="roomy"):
        return False
    _roomy.__code__ = _roomy.__code__.replace(co_stacksize=SLOTS)
    return True


def use_roomy_frames() -> bool:
    """Let :func:`roomy` call from a roomy frame in this process (the ``mixdyn`` command
    calls it first thing); False where CPython's version is not a checked one."""
    _roomy_on["on"] = _roomy_code()
    return _roomy_on["on"]


def roomy(fn: Callable, *args, **kwargs):
    """``fn(*args, **kwargs)``, in the ``mixdyn`` command's process from a frame that sits at
    the start of a 512 KiB chunk of CPython's frame stack.

    CPython (3.11 to 3.13) keeps a thread's frames in chunks of 16 KiB, mapped when a call
    needs a new one and unmapped when it returns: JAX's tracing, deep and repetitive, maps
    and unmaps one ~45,000 times in an empty-cache run of the paper's example (each with
    page faults; 6.7 us instead of 0.04 us a call measured alone). Called from a frame whose
    code declares a large operand stack (never used), the calls ~1,000 frames below stay in
    one large chunk. Elsewhere (a program that imports mixdyn, an unchecked interpreter):
    a plain call."""
    return (_roomy if _roomy_on["on"] else _plain)(fn, *args, **kwargs)


def exit_now(code: int) -> None:
    """End the ``mixdyn`` command's process with ``code`` as a normal exit would, less the
    interpreter's teardown of every module and object (~0.2 s after a run, a tenth of a
    warm run): the threads that are not daemons are joined, the ``atexit`` functions run
    (CPython's ``atexit._run_exitfuncs``: JAX's, logging's, the figure worker's stop), the
    standard streams are flushed, then :func:`os._exit`. Every file mixdyn writes is closed
    before. Public fallback: ``SystemExit(code)``."""
    import atexit

    run_exit_functions = getattr(atexit, "_run_exitfuncs", None)
    if not allowed("python", hook="exit_now") or run_exit_functions is None:
        raise SystemExit(code)
    for thread in threading.enumerate():
        if thread is not threading.current_thread() and not thread.daemon:
            thread.join()
    run_exit_functions()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError, AttributeError):
            stream.flush()
    os._exit(code)


# --------------------------------------------------------------------------- Pillow
def _keep_palette(im, info):
    """Pillow's ``GifImagePlugin._get_optimize`` for frames that share one palette: keep it
    (None: no entries to drop)."""
    return None


@contextlib.contextmanager
def shared_palette():
    """A context for writing a GIF whose frames share one palette (:mod:`mixdyn.viz._draw`)
    in which Pillow keeps that palette instead of remapping each frame to the colours it
    uses (``GifImagePlugin._get_optimize``): the same pictures, ~20% less time for the
    paper example's animation, and unchanged pixels still transparent. Only the ``mixdyn``
    command's figure worker, a process that draws nothing else, writes its GIFs in it
    (``mixdyn.viz._draw.GIF_CONTEXT``). Public fallback: Pillow as it is."""
    if not allowed("pillow", hook="shared_palette"):
        yield
        return
    try:
        from PIL import GifImagePlugin
    except ImportError:  # pragma: no cover - no Pillow: no GIF either
        yield
        return
    original = getattr(GifImagePlugin, "_get_optimize", None)
    if original is None:  # pragma: no cover - a Pillow laid out otherwise
        yield
        return
    GifImagePlugin._get_optimize = _keep_palette
    try:
        yield
    finally:
        GifImagePlugin._get_optimize = original


# --------------------------------------------------------------------------- pytest-xdist
def whole_module_scheduler(config, log, modules: tuple[str, ...]):
    """For mixdyn's test session: pytest-xdist's ``--dist load`` scheduler, but with the test
    modules named in ``modules`` (file names) each sent whole to one worker (its module
    fixtures, long runs, computed once), through xdist's private ``_split_scope``. Public
    fallback: None (xdist's own scheduler; the same tests, those runs once per worker)."""
    if not allowed("pytest-xdist", hook="whole_module_scheduler"):
        return None
    try:
        from xdist.scheduler import LoadScopeScheduling
    except ImportError:  # pragma: no cover - xdist laid out otherwise
        return None

    class Scheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            module = nodeid.split("::", 1)[0]
            return module if module.rsplit("/", 1)[-1] in modules else nodeid

    return Scheduling(config, log)


__all__ = [
    "HOOKS",
    "KNOWN",
    "PUBLIC_ONLY_ENV",
    "SLOTS",
    "allowed",
    "chained_floor",
    "exit_now",
    "public_only",
    "roomy",
    "shared_palette",
    "use_roomy_frames",
    "version",
    "whole_module_scheduler",
]
