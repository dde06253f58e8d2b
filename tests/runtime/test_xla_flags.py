"""mixdyn's XLA CPU options (``mixdyn.runtime._xla``): given to XLA with each of mixdyn's
programs, the flags the user names in ``$XLA_FLAGS`` left to the user, and ``$XLA_FLAGS``
itself, as every other program of the process, untouched."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import jax.numpy as jnp
import pytest

from mixdyn.runtime import _programs, _xla
from mixdyn.runtime._xla import IF_KNOWN, KEEP_ENV, SAFE_FLAGS, flags_to_add, jaxlib_version

SHOW = (
    "import os, json; import mixdyn; from mixdyn.runtime import _xla; "
    "print(json.dumps([os.environ.get('XLA_FLAGS'), _xla.compile_options()]))"
)


def _after_import(env_flags: str | None, keep: bool = False):
    """``($XLA_FLAGS, compile options)`` in a new process after ``import mixdyn``."""
    env = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", KEEP_ENV)}
    if env_flags is not None:
        env["XLA_FLAGS"] = env_flags
    if keep:
        env[KEEP_ENV] = "1"
    out = subprocess.run(
        [sys.executable, "-c", SHOW],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.timeout(300)
def test_the_environment_is_left_and_the_users_flags_are_kept():
    flags, options = _after_import(None)
    assert flags is None
    assert options == {k.lstrip("-"): v == "true" for k, v in flags_to_add().items()}
    assert {k.lstrip("-") for k in SAFE_FLAGS} <= set(options)
    mine = "--xla_cpu_multi_thread_eigen=true --xla_dump_to=/tmp/nowhere"
    flags, options = _after_import(mine)
    assert flags == mine
    assert "xla_cpu_multi_thread_eigen" not in options  # the user's value holds
    assert options["xla_cpu_enable_concurrency_optimized_scheduler"] is False
    assert _after_import(mine, keep=True) == [mine, {}]


def test_mixdyn_programs_are_compiled_with_the_options(monkeypatch):
    """The options reach XLA with every compile of a mixdyn program: an option XLA does not
    know is refused by it (with the cache on and off)."""

    def double(x):
        return 2.0 * x

    ok = _programs.cached_jit(double)
    assert ok.options == _xla.compile_options()
    assert float(ok(jnp.asarray(1.5))) == 3.0
    monkeypatch.setattr(_xla, "compile_options", lambda: {"xla_no_such_option": False})

    def triple(x):
        return 3.0 * x

    with pytest.raises(Exception, match="xla_no_such_option"):
        _programs.cached_jit(triple)(jnp.asarray(1.5))


def test_a_program_called_inside_another_takes_the_outer_options():
    """XLA takes compile options for a whole program only: a mixdyn function called inside
    another jitted function (with traced or with constant arguments) is part of that program,
    with the cache on and off."""
    import jax

    def double(x):
        return 2.0 * x

    f = _programs.cached_jit(double)
    assert f.options  # mixdyn's own options for a program of its own
    folder = _programs.cache_folder()
    try:
        for cache in (False, folder):
            _programs.set_cache(cache)
            assert float(jax.jit(lambda x: f(x) + 1.0)(1.0)) == 3.0
            assert float(jax.jit(lambda x: f(jnp.ones(2)).sum() + x)(1.0)) == 5.0
            assert float(f(jnp.asarray(1.5))) == 3.0
    finally:
        _programs.set_cache(folder or False)


def test_optional_flags_are_added_only_for_the_jaxlibs_checked():
    """A flag of :data:`IF_KNOWN` is added for the jaxlib versions in which it was checked to
    exist (XLA aborts the process on an unknown flag), not before nor after them, and never
    where the user named it."""
    flag = "--xla_cpu_use_fusion_emitters"
    value, first, after = IF_KNOWN[flag]
    assert flags_to_add(version=(0, 5, 0)) == SAFE_FLAGS  # unknown to jaxlib 0.5.0: tried
    assert flags_to_add(version=first)[flag] == value
    assert flags_to_add(version=(0, 10, 2))[flag] == value  # this project's jaxlib: tried
    assert flags_to_add(version=after) == SAFE_FLAGS
    assert flag not in flags_to_add({flag}, version=(0, 10, 2))
    installed = jaxlib_version()
    assert (flag in flags_to_add()) == (installed is not None and first <= installed < after)
