"""Compiled executables kept beside the exported programs of :mod:`mixdyn._compile`.

A program read back from :mod:`jax.export` must still be lowered, keyed and looked up in
JAX's persistent cache before it runs: for the paper's example (18 programs) that is ~0.8 s
of CPU in every process, most of it Python holding the interpreter lock. This layer stores
the XLA executable of each exported program itself, once compiled, and loads it back
without lowering anything (XLA deserializes it: ~0.02 s a program).

An executable is only valid on the XLA that built it, with the same flags, on the same kind
of processor: its file name holds a digest of the platform and its version, ``$XLA_FLAGS``,
the JAX settings that enter XLA's compile options, the devices' topology and the
processor's features (:func:`environment`), besides the exported program's own key
(versions of every library and of mixdyn's source). XLA needs the compile options the
executable was built with to load it; JAX does not hand them out, so :func:`compiled`
watches JAX's persistent cache look-up, which receives them, while it compiles (no
executable is stored where JAX's cache is off or that look-up is not where this version of
JAX has it). What JAX sets up only while lowering (LAPACK's functions for the CPU kernels)
is set up before an executable is loaded. Any failure to store or load one falls back to
the way without it.

Like JAX's cache, the folder is trusted code.
"""

from __future__ import annotations

import functools
import hashlib
import io
import os
import pathlib
import pickle
import platform
import threading

import jax

from ._files import write_pickle

#: The sub-folder of the cache folder holding the executables.
EXECUTABLES = "executables"

_local = threading.local()
_spy_lock = threading.Lock()
_spy = {"installed": False}


def _install_spy() -> bool:
    """Wrap JAX's persistent-cache look-up so that a compile in :func:`compiled` sees its
    compile options (installed once; it only records, for the thread that asked)."""
    with _spy_lock:
        if _spy["installed"]:
            return True
        try:
            from jax._src import compilation_cache as cc

            original = cc.get_executable_and_time
        except (ImportError, AttributeError):
            return False

        @functools.wraps(original)
        def get_executable_and_time(*args, **kwargs):
            if getattr(_local, "armed", False):
                key = kwargs.get("cache_key", args[0] if args else None)
                options = kwargs.get("compile_options", args[1] if len(args) > 1 else None)
                _local.seen = (key, options)
            return original(*args, **kwargs)

        cc.get_executable_and_time = get_executable_and_time
        _spy["installed"] = True
        return True


@functools.cache
def environment() -> str:
    """A digest of what besides the program decides its executable (see the module)."""
    from jax._src import config

    backend = jax.devices()[0].client
    parts = [backend.platform, backend.platform_version]
    parts += [os.environ.get("XLA_FLAGS", ""), os.environ.get("LIBTPU_INIT_ARGS", "")]
    for name in (
        "use_shardy_partitioner",
        "exec_time_optimization_effort",
        "memory_fitting_effort",
        "optimization_level",
        "memory_fitting_level",
        "enable_remat_opt_pass",
        "jax_pjrt_client_create_options",
    ):
        parts.append(f"{name}={getattr(getattr(config, name, None), 'value', None)}")
    try:
        from jax._src.lib import xla_client

        topology = xla_client.get_topology_for_devices(jax.devices()[:1])
        parts.append(str(topology.fingerprint()))
    except Exception:
        parts.append(repr([d.device_kind for d in jax.devices()]))
    parts.append(_processor())
    from jax._src import compilation_cache as cc

    compression = [getattr(cc, name, None) is not None for name in ("zstd", "zstandard")]
    parts.append(f"compression={compression}")  # how a stored entry is compressed
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:24]


def _processor() -> str:
    """The processor's model and features (Linux: ``/proc/cpuinfo``'s first entry)."""
    text = ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                key = line.split(":", 1)[0].strip()
                if key in ("model name", "flags", "Features", "CPU implementer", "CPU part"):
                    text += line
                if not line.strip() and text:
                    break
    except OSError:
        pass
    return text or f"{platform.machine()} {platform.processor()}"


def path_for(folder: str, stem: str) -> pathlib.Path:
    """Where the executable of the exported program ``stem`` is stored in ``folder``."""
    return pathlib.Path(folder, EXECUTABLES, f"{stem}-{environment()}.exe")


def compiled(exported, path: pathlib.Path | None, options: dict | None = None):
    """``exported`` compiled (:class:`jax.stages.Compiled`, through JAX's persistent cache,
    with XLA's compile ``options``, e.g. :data:`mixdyn._compile.QUICK`); its executable
    stored at ``path`` when it can be (see the module)."""
    lowered = jax.jit(exported.call, compiler_options=options).lower(*exported.in_avals)
    armed = path is not None and _install_spy()
    _local.armed, _local.seen = armed, None
    try:
        out = lowered.compile()
    finally:
        seen, _local.armed, _local.seen = _local.seen, False, None
    if armed and seen is not None and seen[0] is not None and seen[1] is not None:
        _store(path, out, *seen)
    return out


def _cached_entry(key: str) -> bytes:
    """The entry under ``key`` in JAX's persistent cache: the executable as XLA serialized
    it after compiling, compressed (an executable that was itself loaded from the cache does
    not serialize again completely: XLA CPU then misses some of its functions when it runs).
    Stored as it is: a sixth of the size, ~1 ms to decompress."""
    from jax._src import compilation_cache as cc

    entry = cc._get_cache(jax.devices()[0].client).get(key)
    if entry is None:
        raise LookupError(key)
    return entry


def _executable(entry: bytes) -> bytes:
    """The serialized executable in a cache entry of JAX's (:func:`_cached_entry`)."""
    from jax._src import compilation_cache as cc

    return cc.extract_executable_and_time(cc.decompress_executable(entry))[0]


def _store(path: pathlib.Path, out, key: str, options) -> None:
    from jax._src.lib import xla_client
    from jax.experimental import serialize_executable as se

    class _Pickler(se._JaxPjrtPickler):
        def persistent_id(self, obj):
            if isinstance(obj, xla_client.LoadedExecutable):
                return ("entry", entry)
            return super().persistent_id(obj)

    try:
        entry = _cached_entry(key)
        unloaded = out._executable._unloaded_executable
        if out._params.const_args or (unloaded.mut is not None and unloaded.mut.in_mut):
            return
        args_info, in_tree = jax.tree_util.tree_flatten(out.args_info)
        with io.BytesIO() as f:
            _Pickler(f).dump((unloaded, args_info, out._no_kwargs))
            payload = f.getvalue()
        blob = (payload, in_tree, out.out_tree, options.SerializeAsString())
        pickle.dumps(blob)
        path.parent.mkdir(exist_ok=True)
    except Exception:  # not stored: the program is still used in memory
        return
    write_pickle(path, blob)


def _handlers_ready(platform_name: str) -> None:
    """Set up what lowering would have set up for the executables' custom calls: on CPU,
    JAX hands LAPACK's functions to its kernels only when it lowers a call of an exported
    program (``jax._src.export._export._ensure_backends_initialized``); an executable
    loaded without lowering would call through null pointers."""
    from jax._src.export import _export

    _export._ensure_backends_initialized((platform_name,))


def load(path: pathlib.Path):
    """The executable stored at ``path`` (:class:`jax.stages.Compiled`); raises
    FileNotFoundError when there is none, anything else when it cannot be loaded."""
    from jax._src.lib import xla_client
    from jax.experimental import serialize_executable as se

    with open(path, "rb") as f:
        payload, in_tree, out_tree, options = pickle.load(f)
    options = xla_client.CompileOptions.ParseFromString(options)
    backend = jax.devices()[0].client
    _handlers_ready(backend.platform)

    class _Unpickler(se._JaxPjrtUnpickler):
        def persistent_load(self, pid):
            if pid[0] == "entry":
                executable = _executable(pid[1])
                return self.backend.deserialize_executable(
                    executable, self.execution_devices, options
                )
            return super().persistent_load(pid)

    unloaded, args_info, no_kwargs = _Unpickler(io.BytesIO(payload), backend).load()
    return jax.stages.Compiled(
        unloaded.load(), [], in_tree.unflatten(args_info), out_tree, no_kwargs=no_kwargs
    )
