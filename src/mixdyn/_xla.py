"""XLA CPU settings that keep mixdyn's compiled loops from hanging.

XLA's CPU runtime has wedged (a deadlock: the process waits forever, using no CPU) on
mixdyn's programs and on others' (a hang of 15 minutes in CI on the 243-coordinate N-four-bar
in two processes at once; PyAutoFit issues 1528/1530: their hangs stopped with
``--xla_cpu_multi_thread_eigen=false`` alone; a vmapped ``while_loop`` here stopped with the
concurrency-optimized scheduler off). mixdyn's matrices are small (a few hundred rows at
most), so Eigen's intra-op thread pool buys nothing: measured on the N = 40 four-bar
(Dopri8, 1e-9), 12-16 s with one thread against 15-21 s with the pool.

:func:`apply` adds these flags to ``$XLA_FLAGS`` on import of mixdyn, before JAX starts its
CPU backend. A flag the user names in ``$XLA_FLAGS`` (either value) is left as the user set
it; ``MIXDYN_KEEP_XLA_FLAGS=1`` leaves ``$XLA_FLAGS`` untouched. Once a JAX backend has
started (JAX used before mixdyn was imported), flags can no longer change and none is added.
"""

from __future__ import annotations

import os
import sys

#: Flag name -> the value mixdyn sets when the user has not named the flag.
SAFE_FLAGS = {
    "--xla_cpu_multi_thread_eigen": "false",
    "--xla_cpu_enable_concurrency_optimized_scheduler": "false",
}

#: The environment variable that keeps ``$XLA_FLAGS`` exactly as the user set it (``1``).
KEEP_ENV = "MIXDYN_KEEP_XLA_FLAGS"


def _backend_started() -> bool:
    if "jax" not in sys.modules:
        return False
    from jax._src import xla_bridge

    return xla_bridge.backends_are_initialized()


def apply() -> tuple[str, ...]:
    """Add the missing :data:`SAFE_FLAGS` to ``$XLA_FLAGS``; returns the flags added."""
    if os.environ.get(KEEP_ENV, "").strip() not in ("", "0") or _backend_started():
        return ()
    current = os.environ.get("XLA_FLAGS", "")
    named = {tok.split("=", 1)[0] for tok in current.split()}
    added = tuple(f"{k}={v}" for k, v in SAFE_FLAGS.items() if k not in named)
    if added:
        os.environ["XLA_FLAGS"] = " ".join([*current.split(), *added])
    return added
