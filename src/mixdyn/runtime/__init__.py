"""mixdyn's runtime: how its programs are compiled, kept between processes and started.

Its public face is small:

- :func:`set_cache` and :func:`cache_folder`: mixdyn's persistent caches (exported traces and
  compiled executables of its own programs, in ``$MIXDYN_CACHE_DIR``, else
  ``~/.cache/mixdyn/jax``); ``MIXDYN_NO_CACHE=1`` turns them off at import;
- :func:`cached_jit`: ``equinox.filter_jit`` whose programs persist in that folder;
- :func:`release`: give back the compiled programs held in memory (a long process that
  compiles thousands of them, a study over many models: each keeps memory mappings, of
  which Linux allows a process 65530 by default).

Behind it, one module a job: ``_programs`` (export, keys, read-ahead), ``_executables``
(stored executables), ``_files`` (atomic writes), ``_xla`` (the XLA CPU options of its
programs), ``_command`` and ``_worker`` (what the ``mixdyn`` command does in its own process: its
figure worker, the collector's pace), ``_clip_floor`` and ``_private``: every private part
of JAX, diffrax or CPython that mixdyn uses, each behind a version check with a public
fallback (``MIXDYN_PUBLIC_ONLY=1`` takes the public path everywhere).

This package imports JAX only when one of its public names is first used: the command's
start-up (``_command``) runs before JAX is imported.
"""

from __future__ import annotations

_PUBLIC = {"set_cache", "cache_folder", "cached_jit", "release"}


def __getattr__(name: str):
    if name in _PUBLIC:
        from . import _programs

        return getattr(_programs, name)
    raise AttributeError(f"module 'mixdyn.runtime' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(_PUBLIC)


__all__ = ["cache_folder", "cached_jit", "release", "set_cache"]
