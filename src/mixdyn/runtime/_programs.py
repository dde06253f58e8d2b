"""Compiled programs kept between processes: the persistent caches of mixdyn.

Two layers, both in one folder (``$MIXDYN_CACHE_DIR``, else ``$XDG_CACHE_HOME/mixdyn/jax``,
else ``~/.cache/mixdyn/jax``), on by default in the Python API and the CLI alike:

- the *traced* programs of mixdyn's jitted functions, exported with :mod:`jax.export` per
  model structure (:func:`cached_jit`): a later process reads one back without running any
  Python of the function (tracing an integrator takes seconds);
- the executable of each exported program once compiled (:mod:`mixdyn.runtime._executables`),
  so that a later process runs it without lowering or compiling it.

JAX's own persistent compilation cache is not touched: it stays as the user set it.

A program is keyed by the function (module and qualified name), everything about its
arguments that is not an array (the PyTree structure with every static field of the
equinox modules: the mechanism's structure, element names, expression trees...), the
shapes, dtypes and weak types of the array leaves (the model's numbers: changing them
reuses the program), and the versions of Python, jax, jaxlib, equinox, diffrax, lineax,
optimistix and of mixdyn's own source (a digest of its files), the backend and the
x64 flag. Arguments that cannot be keyed safely across processes (a function or class
defined outside mixdyn and the libraries above, e.g. in a user's script, or anything that
cannot be pickled) are not exported: those calls are traced as before (``equinox.filter_jit``),
as are programs that JAX cannot export (host callbacks such as a progress callback).

A function that runs once or a few times per analysis (assembly steps, rank checks, the
consistent start) is declared ``cached_jit(fn, optimize=False)``: XLA compiles it without
LLVM's optimizations (:data:`QUICK`), ~40% less compile time (the paper example's checks: an
empty-cache run ~0.8 s shorter) for code ~2.5 times slower that runs for microseconds.
Loops over time (integrators, kinematic and sweep loops, the post-processing of every output
time) keep XLA's full optimization. The setting is the function's own, the same with the
cache on and off (``equinox.filter_jit``'s ``compiler_options``) and stored with its
program; results differ from an optimized compile in the last bits (~1e-12 relative).

Every program is compiled with mixdyn's XLA CPU options
(:func:`mixdyn.runtime._xla.compile_options`), its own and nobody else's.

Switches: ``MIXDYN_NO_CACHE=1`` (read when mixdyn is imported) or :func:`set_cache`. The cache
folder is trusted code, as JAX's own cache is: do not share it with users you do not trust.
"""

from __future__ import annotations

import collections
import contextlib
import functools
import hashlib
import importlib.metadata
import io
import os
import pathlib
import pickle
import sys
import threading
import types
from collections.abc import Callable

import equinox as eqx
import jax
from jax import export as _export

from . import _executables, _files, _xla
from ._private import roomy

#: The environment variable that turns every persistent cache off (``1``).
NO_CACHE_ENV = "MIXDYN_NO_CACHE"
#: The environment variable naming the cache folder.
CACHE_DIR_ENV = "MIXDYN_CACHE_DIR"
#: The sub-folder of the cache folder holding the exported (traced) programs.
EXPORTED = "exported"

#: XLA's compile options for a ``cached_jit(fn, optimize=False)`` function: LLVM at -O0.
QUICK = {"xla_backend_optimization_level": 0}

_state = {"folder": None}
_lock = threading.Lock()
#: Every :func:`cached_jit` function of this process (their programs: :func:`release`).
_cached: list[_CachedJit] = []

#: Modules whose functions and classes may appear (by name) in a key: their code is covered
#: by the versions in the key. Anything else (a user's ``__main__``) is not keyed.
_TRUSTED_MODULES = (
    "mixdyn",
    "jax",
    "jaxlib",
    "equinox",
    "diffrax",
    "lineax",
    "optimistix",
    "numpy",
    "math",
    "operator",
    "builtins",
    "functools",
    "collections",
    "typing",
)
_DISTRIBUTIONS = ("jax", "jaxlib", "equinox", "diffrax", "lineax", "optimistix", "numpy")


def default_folder() -> str:
    """The cache folder from the environment (``$MIXDYN_CACHE_DIR``, ``$XDG_CACHE_HOME``)."""
    folder = os.environ.get(CACHE_DIR_ENV)
    if not folder:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        folder = os.path.join(base, "mixdyn", "jax")
    return folder


def set_cache(enabled: bool | str | os.PathLike = True) -> str | None:
    """Turn mixdyn's persistent caches on or off for this process.

    They hold mixdyn's own programs (exported traces and their executables) and nothing
    else: JAX's own persistent compilation cache is left as the user set it, on or off.

    Args:
        enabled: True (the default folder, see the module's documentation), a folder, or
            False (nothing is read from or written to disk by mixdyn; programs are traced and
            compiled in each process).

    Returns:
        The cache folder in use, or None when off (or when the folder cannot be created: a
        cache is an optimisation, never a failure).
    """
    with _lock:
        folder = None
        if enabled is not False and enabled is not None:
            folder = default_folder() if enabled is True else os.fspath(enabled)
            try:
                os.makedirs(os.path.join(folder, EXPORTED), exist_ok=True)
            except OSError:
                folder = None
        _state["folder"] = folder
        return folder


def cache_folder() -> str | None:
    """The cache folder in use, or None when the persistent caches are off."""
    return _state["folder"]


def configure_from_env() -> str | None:
    """The default at import: on, unless ``MIXDYN_NO_CACHE`` is set to something else than
    ``0`` or empty."""
    if os.environ.get(NO_CACHE_ENV, "").strip() not in ("", "0"):
        return set_cache(False)
    return set_cache(True)


# --------------------------------------------------------------------------- keys
class _UncacheableError(Exception):
    """An argument that cannot be keyed safely across processes."""


class _Aval:
    """An array leaf in a key: its shape, dtype and weak type only."""

    __slots__ = ("dtype", "shape", "weak")

    def __init__(self, x):
        self.shape = tuple(x.shape)
        self.dtype = str(x.dtype)
        self.weak = bool(getattr(x, "weak_type", False))

    def __reduce__(self):
        return (_Aval._of, (self.shape, self.dtype, self.weak))

    @staticmethod
    def _of(shape, dtype, weak):  # pragma: no cover - keys are never unpickled
        raise TypeError


class _Leaf:
    """A placeholder for an output array leaf (its index in the flat outputs)."""

    __slots__ = ("i",)

    def __init__(self, i: int):
        self.i = i

    def __reduce__(self):
        return (_Leaf, (self.i,))


def _trusted(module: str | None) -> bool:
    root = (module or "").split(".")[0]
    return root in _TRUSTED_MODULES


#: Classes whose instances are keyed by a function of them (:func:`register_key`).
_KEYS: dict[type, Callable] = {}


def register_key(cls: type, key: Callable) -> None:
    """Key the instances of ``cls`` (in a static part of the arguments) by ``key(obj)``: data
    that decides the traced program, the same in every process (arrays in it count by shape
    and dtype only). For classes that compare by identity or that hold numbers they do not
    use when traced."""
    _KEYS[cls] = key


def skeleton(tree):
    """``tree`` with its array leaves replaced by their shape, dtype and weak type."""
    leaves, treedef = jax.tree_util.tree_flatten(tree)
    return treedef.unflatten([_Aval(x) if eqx.is_array(x) else x for x in leaves])


def _keyed(name, data):  # pragma: no cover - keys are never unpickled
    raise TypeError


class _KeyPickler(pickle.Pickler):
    """Pickles a key; refuses functions and classes whose code the key's versions do not
    cover (a name in ``__main__`` may mean other code in another process)."""

    def reducer_override(self, obj):
        key = _KEYS.get(type(obj))
        if key is not None:
            return (_keyed, (type(obj).__qualname__, key(obj)))
        if isinstance(obj, type | types.FunctionType | types.BuiltinFunctionType):
            if not _trusted(getattr(obj, "__module__", None)) or "<locals>" in getattr(
                obj, "__qualname__", "<locals>"
            ):
                raise _UncacheableError(repr(obj))
        elif isinstance(obj, jax.Array):
            raise _UncacheableError("an array among the static parts")
        return NotImplemented


def _key_bytes(obj) -> bytes:
    buf = io.BytesIO()
    try:
        _KeyPickler(buf, protocol=5).dump(obj)
    except _UncacheableError:
        raise
    except Exception as e:  # not picklable: not keyable
        raise _UncacheableError(str(e)) from None
    return buf.getvalue()


@functools.cache
def _environment() -> bytes:
    """What besides the arguments decides a traced program: versions, mixdyn's source,
    the backend and the JAX settings that change tracing."""
    parts = [sys.version, jax.default_backend(), str(jax.config.jax_enable_x64)]
    for name in _DISTRIBUTIONS:
        try:
            parts.append(f"{name}={importlib.metadata.version(name)}")
        except importlib.metadata.PackageNotFoundError:
            parts.append(f"{name}=?")
    for flag in (
        "jax_default_matmul_precision",
        "jax_numpy_rank_promotion",
        "jax_numpy_dtype_promotion",
    ):
        parts.append(f"{flag}={getattr(jax.config, flag, None)}")
    h = hashlib.sha256("\n".join(parts).encode())
    root = pathlib.Path(__file__).parent.parent
    for path in sorted(root.rglob("*.py")):
        if path.name == "cli.py" or path.parent.name == "viz":
            continue  # never traced: editing them keeps the programs
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return h.digest()


# --------------------------------------------------------------------------- the wrapper
class _Program:
    """A loaded program: the compiled exported function and the outputs' shape. Without
    ``compiled`` it is compiled at its first call (its executable then stored at ``exe``:
    :mod:`mixdyn.runtime._executables`)."""

    __slots__ = ("call", "exe", "exported", "leaves", "options", "treedef")

    def __init__(
        self, exported: _export.Exported | None, skeleton, compiled=None, exe=None, options=None
    ):
        self.exported, self.call, self.exe, self.options = exported, compiled, exe, options
        self.leaves, self.treedef = jax.tree_util.tree_flatten(skeleton)

    @classmethod
    def of(cls, blob, exe) -> _Program:
        """The program of a stored ``blob`` (:meth:`_CachedJit._export`), to be compiled at
        its first call (its executable then stored at ``exe``)."""
        return cls(_export.deserialize(bytearray(blob[0])), blob[1], exe=exe, options=blob[2])

    def compile(self) -> None:
        """Compile it now, if not compiled yet (and store its executable)."""
        if self.call is None:
            self.call = _executables.compiled(self.exported, self.exe, self.options)
            self.exported = None

    def __call__(self, dynamic):
        self.compile()
        flat = self.call(*dynamic)
        out = [flat[x.i] if isinstance(x, _Leaf) else x for x in self.leaves]
        return jax.tree_util.tree_unflatten(self.treedef, out)


#: Counters of this process (for tests and profiling): programs traced by export, read
#: from disk (of which read ahead, and loaded as executables), calls that fell back to
#: tracing, and programs that a call found prepared in advance (``ahead``).
stats = {
    "exported": 0,
    "loaded": 0,
    "fallback": 0,
    "prefetched": 0,
    "executables": 0,
    "ahead": 0,
}
#: What to do before this process first compiles a program from scratch (traced and
#: compiled, not read from the cache): ``mixdyn run`` off a terminal says so in one line
#: (:func:`on_first_compile`). Emptied when called.
_first_compile: list[Callable[[], None]] = []


def on_first_compile(fn: Callable[[], None] | None) -> None:
    """Call ``fn()`` once, before this process first compiles a program from scratch (a
    program the cache does not hold, or any first program with the cache off); None: nothing."""
    _first_compile[:] = [] if fn is None else [fn]


def _compiling() -> None:
    """A program is compiled from scratch: the :func:`on_first_compile` notice, once."""
    with _lock:
        todo = _first_compile[:]
        _first_compile.clear()
    for fn in todo:
        fn()


#: How many times the Python body of each :func:`cached_jit` function ran, i.e. was traced
#: (by ``filter_jit`` or by export), by ``module.qualname``.
traces: collections.Counter = collections.Counter()


def _counting(fn: Callable, name: str) -> Callable:
    """``fn`` counting its calls in :data:`traces` (its body runs only when traced)."""

    @functools.wraps(fn)
    def traced(*args, **kwargs):
        traces[name] += 1
        return fn(*args, **kwargs)

    return traced


class _CachedJit:
    def __init__(self, fn: Callable, optimize: bool = True):
        self.name = f"{fn.__module__}.{fn.__qualname__}"
        self.fn = _counting(fn, self.name)
        self.options = {**_xla.compile_options(), **({} if optimize else QUICK)} or None
        self.top = eqx.filter_jit(self.fn, compiler_options=self.options)
        self.nested = eqx.filter_jit(self.fn)  # inside another program: that one's options
        self.programs: dict = {}
        functools.update_wrapper(self, fn, updated=())
        _cached.append(self)

    def __get__(self, obj, objtype=None):  # pragma: no cover - used on plain functions
        return self if obj is None else types.MethodType(self, obj)

    def jit(self, *args, **kwargs):
        """The call traced by ``equinox.filter_jit``: with this function's compile options
        (:attr:`options`) as a program of its own, without them inside another program
        (XLA takes options only for a whole program: the outer one's hold)."""
        leaves = jax.tree_util.tree_leaves((args, kwargs))
        if self.options is None or any(isinstance(x, jax.core.Tracer) for x in leaves):
            return self.nested(*args, **kwargs)
        try:
            return self.top(*args, **kwargs)
        except ValueError as e:  # called inside another trace with constant arguments only
            if "top-level" not in str(e):
                raise
            return self.nested(*args, **kwargs)

    @staticmethod
    def _key(args, kwargs):
        """``(leaves, treedef, dynamic, key)`` of a call: its flat arguments, the arrays
        among them and its key in :attr:`programs` (structure, static parts, shapes); None
        inside another trace (nothing to cache)."""
        leaves, treedef = jax.tree_util.tree_flatten((args, kwargs))
        if any(isinstance(x, jax.core.Tracer) for x in leaves):
            return None
        dynamic = [x for x in leaves if eqx.is_array(x)]
        static = tuple(None if eqx.is_array(x) else x for x in leaves)
        # the dtype itself (hashable, equal by value): its str() costs ~3 us a leaf, a
        # quarter millisecond a call of ~75 leaves
        avals = tuple((x.shape, x.dtype, bool(getattr(x, "weak_type", False))) for x in dynamic)
        return leaves, treedef, dynamic, (treedef, static, avals)

    def __call__(self, *args, **kwargs):
        folder = _state["folder"]
        called = None if folder is None else self._key(args, kwargs)
        if called is None:
            if folder is None and _first_compile:
                _compiling()
            return self.jit(*args, **kwargs)
        leaves, treedef, dynamic, mkey = called
        try:
            program = self.programs.get(mkey)
        except TypeError:  # an unhashable static part: as filter_jit would refuse it
            return self.jit(*args, **kwargs)
        if isinstance(program, _Pending):  # being prepared by ahead(): wait for it
            program = program.get()
            if program is None:
                self.programs.pop(mkey, None)  # it failed there: prepared here instead
            else:
                self.programs[mkey] = program
                stats["ahead"] += 1
        if program is None:
            program = self._load(folder, args, kwargs, leaves, treedef)
            self.programs[mkey] = program
        if program is False:
            stats["fallback"] += 1
            return self.jit(*args, **kwargs)
        return program(dynamic)

    def ahead(self, *args, **kwargs) -> None:
        """Prepare the program for these arguments in a background thread (read from the
        cache, else traced, exported and written; compiled), while the caller goes on: a
        run's post-processing while its integrator is traced and compiled (XLA compiles
        without holding the interpreter lock, so two programs compile at once). Only the
        arguments' structure, shapes and dtypes count (arrays of zeros will do); a call
        with these arguments then waits for the program instead of preparing it again.
        Nothing happens with the cache off, inside a trace, or when the program is there."""
        folder = _state["folder"]
        called = None if folder is None else self._key(args, kwargs)
        if called is None:
            return
        leaves, treedef, _, mkey = called
        pending = _Pending()
        with _lock:
            try:
                if mkey in self.programs:
                    return
            except TypeError:  # unhashable: its call is traced by filter_jit
                return
            self.programs[mkey] = pending

        def prepare():
            try:
                program = self._load(folder, args, kwargs, leaves, treedef)
                if isinstance(program, _Program):
                    program.compile()
                pending.value = program
            except Exception:  # the caller prepares it itself
                pending.value = None
            finally:
                pending.done.set()

        threading.Thread(target=prepare, name="mixdyn-ahead", daemon=True).start()

    def _load(self, folder, args, kwargs, leaves, treedef):
        """The program for these arguments: from disk, else exported (and written), else
        False (traced by filter_jit at each new structure, as without a cache)."""
        try:
            shape = treedef.unflatten([_Aval(x) if eqx.is_array(x) else x for x in leaves])
            key = hashlib.sha256(
                _environment() + self.name.encode() + _key_bytes(shape)
            ).hexdigest()
        except _UncacheableError:
            return False
        path = pathlib.Path(folder, EXPORTED, f"{self.name.rsplit('.', 1)[-1]}-{key}.bin")
        _used.append(path.name)
        pending = _prefetched.get(str(path))
        if pending is not None:
            program = pending.get()
            if program is not None:
                stats["prefetched"] += 1
                return program
        try:
            program = _read(path)
            if program is not False:
                stats["loaded"] += 1
            return program
        except FileNotFoundError:
            pass
        except Exception:  # a damaged entry: export it again
            pass
        _compiling()
        blob = self._export(args, kwargs, leaves, treedef)
        _files.write_pickle(path, blob)
        if blob is None:
            return False
        stats["exported"] += 1
        return _Program.of(blob, _executables.path_for(folder, path.stem))

    def _export(self, args, kwargs, leaves, treedef):
        """``(serialized program, output skeleton, compile options)``, or None where JAX
        cannot export it."""
        is_dyn = [eqx.is_array(x) for x in leaves]
        specs = [
            jax.ShapeDtypeStruct(x.shape, x.dtype, weak_type=bool(getattr(x, "weak_type", False)))
            for x, d in zip(leaves, is_dyn, strict=True)
            if d
        ]
        out_static = {}

        def flat(*dynamic):
            it = iter(dynamic)
            full = [next(it) if d else x for x, d in zip(leaves, is_dyn, strict=True)]
            a, k = jax.tree_util.tree_unflatten(treedef, full)
            out = self.fn(*a, **k)
            out_leaves, out_tree = jax.tree_util.tree_flatten(out)
            arrays = [x for x in out_leaves if eqx.is_array(x)]
            n = iter(range(len(arrays)))
            out_static["skeleton"] = jax.tree_util.tree_unflatten(
                out_tree, [_Leaf(next(n)) if eqx.is_array(x) else x for x in out_leaves]
            )
            return arrays

        try:
            exported = roomy(_export.export(jax.jit(flat)), *specs)
            blob = (bytes(exported.serialize()), out_static["skeleton"], self.options)
            pickle.dumps(blob)
        except Exception:
            return None
        return blob


def _read(path, compile: bool = False):
    """The program stored at ``path``: a :class:`_Program` (its stored executable, else
    compiled now if ``compile``, else at its first call), False where an earlier process
    found it not exportable."""
    path = pathlib.Path(path)
    with open(path, "rb") as f:
        blob = pickle.load(f)
    if blob is None:
        return False  # not exportable (recorded by an earlier process)
    exe = _executables.path_for(path.parent.parent, path.stem)
    try:
        program = _Program(None, blob[1], _executables.load(exe))
        stats["executables"] += 1
        return program
    except Exception:  # none stored (or stale, damaged): compiled again, and stored
        pass
    program = _Program.of(blob, exe)
    if compile:  # compiled in this thread (and its executable stored)
        program.compile()
    return program


# --------------------------------------------------------------------------- prefetching
#: The sub-folder of the cache folder holding the manifests of jobs (:func:`remember`).
MANIFESTS = "manifests"
#: Names of the program files this process used, in order (for :func:`remember`).
_used: list[str] = []
#: Programs being read by the prefetching thread, by path.
_prefetched: dict[str, _Pending] = {}
_stop = threading.Event()


class _Pending:
    """A program the prefetching thread reads: :meth:`get` waits for it (None if it could
    not be read: the caller reads or exports it itself)."""

    __slots__ = ("done", "value")

    def __init__(self):
        self.done = threading.Event()
        self.value = None

    def get(self):
        self.done.wait()
        return self.value


def _manifest(folder: str, tag: str) -> pathlib.Path:
    digest = hashlib.sha256(_environment() + tag.encode()).hexdigest()[:40]
    return pathlib.Path(folder, MANIFESTS, f"{digest}.txt")


def prefetch(tag: str) -> int:
    """Start reading, in a background thread, the programs that the last job named ``tag``
    used (recorded by :func:`remember`), in the order it used them, so that they are ready
    when this job asks for them.

    Reading a program (its executable from JAX's cache) is mostly C++ that runs beside the
    job's own Python (importing, checking, assembling). A job whose structure changed since
    asks for other programs: the ones read ahead are left unused, nothing else changes.

    Args:
        tag: names the job, e.g. ``"run:/abs/path/model.yaml"``.

    Returns:
        The number of programs queued (0 with the cache off or no manifest).
    """
    folder = _state["folder"]
    if folder is None:
        return 0
    try:
        names = _manifest(folder, tag).read_text().split()
    except OSError:
        return 0
    _state["manifest"] = bool(names)
    queued = []
    with _lock:
        for name in names:
            if not name.endswith(".bin") or os.sep in name or name.startswith("."):
                continue  # only plain names of this folder's programs
            path = str(pathlib.Path(folder, EXPORTED, name))
            if path not in _prefetched and os.path.exists(path):
                _prefetched[path] = _Pending()
                queued.append(path)
    if queued:
        _stop.clear()
        threading.Thread(target=_read_ahead, args=(queued,), name="mixdyn-prefetch").start()
    return len(queued)


def reading_ahead() -> bool:
    """Whether the running job (:func:`job`) has a manifest of its last run's programs
    (:func:`prefetch`): they are then on disk already, and preparing them in advance gains
    nothing."""
    return _state.get("manifest", False)


def _read_ahead(paths: list[str]) -> None:
    for path in paths:
        pending = _prefetched[path]
        try:
            if not _stop.is_set():
                pending.value = _read(path, compile=True)
        except Exception:  # the job reads or exports it itself
            pending.value = None
        finally:
            pending.done.set()


def stop_prefetch() -> None:
    """Let the prefetching thread stop after the program it is reading (a job that ends
    early, e.g. on an input error, does not wait for the rest)."""
    _stop.set()


def remember(tag: str, since: int = 0) -> None:
    """Record the programs this process used (in order; from the ``since``-th on) as the
    manifest of job ``tag``, for :func:`prefetch` in the next process. Nothing is written
    with the cache off."""
    folder = _state["folder"]
    used = _used[since:]
    if folder is None or not used:
        return
    path = _manifest(folder, tag)
    text = "\n".join(dict.fromkeys(used)) + "\n"
    try:
        if path.exists() and path.read_text() == text:
            return
        path.parent.mkdir(exist_ok=True)
    except OSError:
        return
    _files.write_text(path, text)


@contextlib.contextmanager
def job(tag: str):
    """A job whose programs are read ahead from its last run's manifest, and whose
    programs are recorded as its manifest when it ends without an exception::

        with job(f"run:{path}"):
            ...  # the runs of a model file
    """
    since = len(_used)
    _state["manifest"] = False
    prefetch(tag)
    try:
        yield
    finally:
        stop_prefetch()
        _state["manifest"] = False  # the job's alone: a later job or run starts afresh
    remember(tag, since)


#: The share of the system's limit on memory mappings (``vm.max_map_count``) above which a
#: long process gives back its compiled programs (:func:`release_if_crowded`).
CROWDED = 0.5


def memory_mappings() -> tuple[int, int]:
    """``(mappings, limit)``: this process's memory mappings and the system's limit on them
    (Linux: ``/proc/self/maps``, ``vm.max_map_count``; ``(0, 1)`` where there is no
    ``/proc``). Reading them costs ~2 ms per 1,000 mappings."""
    try:
        with open("/proc/sys/vm/max_map_count") as f:
            limit = int(f.read())
        with open("/proc/self/maps", "rb") as f:
            return f.read().count(b"\n"), limit
    except (OSError, ValueError):
        return 0, 1


def release_if_crowded(share: float | None = None) -> bool:
    """:func:`release` where this process holds more than ``share`` (default
    :data:`CROWDED`) of the memory mappings the system allows it; whether it did."""
    mappings, limit = memory_mappings()
    if mappings <= (CROWDED if share is None else share) * limit:
        return False
    release()
    return True


def release() -> int:
    """Drop the compiled programs this process holds in memory: those of every
    :func:`cached_jit` function (read again from the cache folder at their next call, in
    ~0.02 s each) and JAX's own (:func:`jax.clear_caches`: traced and compiled again).

    Each compiled XLA CPU program keeps its code in a few dozen memory mappings, and a
    process may hold at most ``vm.max_map_count`` of them (65530 by default on Linux); at
    that limit XLA cannot map the next program and the process crashes. A long process
    that compiles thousands of programs (a test session, a study over many models) calls
    this now and then. Programs being prepared in the background are kept. Returns how
    many of mixdyn's programs were dropped."""
    dropped = 0
    with _lock:
        for fn in _cached:
            for key, program in list(fn.programs.items()):
                if not isinstance(program, _Pending):
                    del fn.programs[key]
                    dropped += 1
    jax.clear_caches()
    return dropped


def cached_jit(fn: Callable | None = None, *, optimize: bool = True) -> Callable:
    """``equinox.filter_jit`` whose traced programs persist in the cache folder.

    Arrays are the arguments of the program; everything else is part of its key. Inside
    another trace, with the cache off, or for arguments that cannot be keyed or exported, it
    is ``equinox.filter_jit(fn)``. ``optimize=False`` (as ``@cached_jit(optimize=False)``):
    compiled without LLVM's optimizations (:data:`QUICK`), for a function that runs only a
    few times per analysis (see the module).
    """
    if fn is None:
        return functools.partial(_CachedJit, optimize=optimize)
    return _CachedJit(fn, optimize)


__all__ = [
    "cache_folder",
    "cached_jit",
    "configure_from_env",
    "job",
    "memory_mappings",
    "on_first_compile",
    "prefetch",
    "reading_ahead",
    "register_key",
    "release",
    "release_if_crowded",
    "remember",
    "set_cache",
    "skeleton",
    "stats",
    "stop_prefetch",
    "traces",
]
