"""Compiled executables kept beside the exported programs of :mod:`mixdyn.runtime._programs`.

A program read back from :mod:`jax.export` must still be lowered and compiled before it
runs: for the paper's example (18 programs) that is seconds of CPU in every process. This
layer stores the XLA executable of each exported program once compiled, with JAX's public
:mod:`jax.experimental.serialize_executable`, and loads it back without lowering anything
(XLA deserializes it: ~0.02 s a program).

An executable is only valid on the XLA that built it, with the same flags, on the same kind
of processor: its file name holds a digest of the platform and its version, ``$XLA_FLAGS``,
the JAX settings that enter XLA's compile options, the devices and the processor's features
(:func:`environment`), besides the exported program's own key (versions of every library
and of mixdyn's source). Only an executable that XLA compiled in this process is stored: one
that JAX took from its own persistent cache (where a user turned that on) does not
serialize again completely on the CPU, so a compile that JAX reports as such a hit
(:mod:`jax.monitoring`'s ``/jax/compilation_cache/cache_hits`` event, in the compiling
thread) stores nothing. On the CPU, JAX hands LAPACK's functions to its kernels when it
lowers a call of an exported program; :func:`_handlers_ready` lowers a trivial one before
the first executable is loaded. Any failure to store or load one falls back to the way
without it.

Like JAX's cache, the folder is trusted code.
"""

from __future__ import annotations

import functools
import hashlib
import os
import pathlib
import pickle
import platform
import threading

import jax

from ._files import write_pickle

#: The sub-folder of the cache folder holding the executables.
EXECUTABLES = "executables"
#: The :mod:`jax.monitoring` event of a compile answered from JAX's persistent cache.
CACHE_HIT = "/jax/compilation_cache/cache_hits"

_local = threading.local()


@functools.cache
def _listening() -> bool:
    """Listen (once) for JAX's persistent-cache hits, noting them for the compiling thread."""

    def listener(event: str, **kwargs) -> None:
        if event == CACHE_HIT:
            _local.hit = True

    jax.monitoring.register_event_listener(listener)
    return True


#: JAX settings that enter XLA's compile options (read where this JAX has them).
_SETTINGS = (
    "jax_use_shardy_partitioner",
    "jax_exec_time_optimization_effort",
    "jax_memory_fitting_effort",
    "jax_optimization_level",
    "jax_memory_fitting_level",
    "jax_enable_remat_opt_pass",
    "jax_pjrt_client_create_options",
)


@functools.cache
def environment() -> str:
    """A digest of what besides the program decides its executable (see the module)."""
    backend = jax.devices()[0].client
    parts = [backend.platform, backend.platform_version, jax.__version__]
    parts += [os.environ.get("XLA_FLAGS", ""), os.environ.get("LIBTPU_INIT_ARGS", "")]
    parts += [f"{name}={getattr(jax.config, name, None)}" for name in _SETTINGS]
    parts.append(repr([(d.platform, d.device_kind) for d in jax.devices()]))
    parts.append(_processor())
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
    """``exported`` compiled (:class:`jax.stages.Compiled`, with XLA's compile ``options``,
    e.g. :data:`mixdyn.runtime._programs.QUICK`); its executable stored at ``path`` when XLA
    compiled it here (see the module)."""
    lowered = jax.jit(exported.call, compiler_options=options).lower(*exported.in_avals)
    store = path is not None and _listening()
    _local.hit = False
    out = lowered.compile()
    if store and not _local.hit:
        _store(path, out)
    return out


def _store(path: pathlib.Path, out) -> None:
    from jax.experimental import serialize_executable

    try:
        blob = serialize_executable.serialize(out)
        pickle.dumps(blob)
        path.parent.mkdir(exist_ok=True)
    except Exception:  # not stored: the program is still used in memory
        return
    write_pickle(path, blob)


@functools.cache
def _handlers_ready(platform_name: str) -> bool:
    """Set up what lowering sets up for an executable's custom calls (on the CPU, LAPACK's
    functions for JAX's kernels, handed over when a call of an exported program is lowered;
    an executable loaded without any lowering would call through null pointers): lower a
    call of a trivial exported program, once per platform."""
    spec = jax.ShapeDtypeStruct((), "float32")
    exported = jax.export.export(jax.jit(lambda x: x), platforms=[platform_name])(spec)
    jax.jit(exported.call).lower(spec)
    return True


def load(path: pathlib.Path):
    """The executable stored at ``path`` (:class:`jax.stages.Compiled`); raises
    FileNotFoundError when there is none, anything else when it cannot be loaded."""
    from jax.experimental import serialize_executable

    with open(path, "rb") as f:
        payload, in_tree, out_tree = pickle.load(f)
    backend = jax.devices()[0].client
    _handlers_ready(backend.platform)
    return serialize_executable.deserialize_and_load(payload, in_tree, out_tree, backend)
