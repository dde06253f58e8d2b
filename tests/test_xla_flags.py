"""mixdyn's XLA CPU flags (``mixdyn._xla``): added on import where the user named none,
the user's own values kept, nothing changed once JAX's backend has started."""

from __future__ import annotations

import importlib.metadata
import json
import os
import subprocess
import sys

import pytest

from mixdyn._xla import IF_KNOWN, KEEP_ENV, SAFE_FLAGS, _known, _recent_jaxlib, flags_to_add

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


def test_optional_flags_are_added_only_where_jaxlib_knows_them():
    """A flag name is looked up in jaxlib's libraries: one every XLA has is found, a made-up
    one is not (XLA would abort the process on it), and the optional flags are added exactly
    where found."""
    real, fake = "--xla_cpu_multi_thread_eigen", "--xla_cpu_no_such_flag_in_any_xla"
    assert _known([real, fake]) == ({real} if _recent_jaxlib() else set())
    optional = set(flags_to_add()) - set(SAFE_FLAGS)
    assert optional == _known(list(IF_KNOWN))
    assert flags_to_add(set(IF_KNOWN)).keys() == SAFE_FLAGS.keys()


def test_an_older_jaxlib_is_not_searched(monkeypatch):
    """Below :data:`RECENT_JAXLIB` no library is read and only the safe flags are added."""
    import mixdyn._xla as x

    monkeypatch.setattr(x, "_recent_jaxlib", lambda: False)
    assert x._known(["--xla_cpu_multi_thread_eigen"]) == set()
    assert x.flags_to_add() == SAFE_FLAGS
    monkeypatch.undo()
    monkeypatch.setattr(importlib.metadata, "version", lambda name: "0.5.3")
    assert not x._recent_jaxlib()
    monkeypatch.setattr(importlib.metadata, "version", lambda name: "0.10.2")
    assert x._recent_jaxlib()
