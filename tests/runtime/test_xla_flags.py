"""mixdyn's XLA CPU flags (``mixdyn.runtime._xla``): added on import where the user named none,
the user's own values kept, nothing changed once JAX's backend has started."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from mixdyn.runtime._xla import IF_KNOWN, KEEP_ENV, SAFE_FLAGS, flags_to_add, jaxlib_version

SHOW = "import os, json; {pre}import mixdyn; print(json.dumps(os.environ.get('XLA_FLAGS')))"


def _flags_after_import(env_flags: str | None, pre: str = "", keep: bool = False):
    env = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", KEEP_ENV)}
    if env_flags is not None:
        env["XLA_FLAGS"] = env_flags
    if keep:
        env[KEEP_ENV] = "1"
    out = subprocess.run(
        [sys.executable, "-c", SHOW.format(pre=pre)],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def _parse(flags: str | None) -> dict[str, str]:
    return dict(tok.split("=", 1) for tok in (flags or "").split())


@pytest.mark.timeout(300)
def test_flags_are_added_and_the_users_are_kept():
    added = _parse(_flags_after_import(None))
    assert added == flags_to_add()
    assert SAFE_FLAGS.items() <= added.items()
    mine = "--xla_cpu_multi_thread_eigen=true --xla_dump_to=/tmp/nowhere"
    got = _parse(_flags_after_import(mine))
    assert got["--xla_cpu_multi_thread_eigen"] == "true"
    assert got["--xla_dump_to"] == "/tmp/nowhere"
    assert got["--xla_cpu_enable_concurrency_optimized_scheduler"] == "false"
    assert _flags_after_import(mine, keep=True) == mine
    assert _flags_after_import(None, keep=True) is None


@pytest.mark.timeout(300)
def test_nothing_is_added_once_jax_has_started():
    started = "import jax.numpy as jnp; jnp.ones(2).block_until_ready(); "
    assert _flags_after_import(None, pre=started) is None


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
