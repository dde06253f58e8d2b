"""The cyclic garbage collector held off during a sweep's set-up loops
(:func:`mixdyn.analysis._schedule.collector_paused`) is set back as the caller had it."""

from __future__ import annotations

import gc

import pytest

from mixdyn.analysis._schedule import collector_paused


@pytest.fixture
def restore_gc():
    was = gc.isenabled()
    yield
    (gc.enable if was else gc.disable)()


@pytest.mark.parametrize("enabled", [True, False])
def test_the_collector_is_held_off_within_and_set_back_after(restore_gc, enabled):
    (gc.enable if enabled else gc.disable)()
    with collector_paused():
        assert not gc.isenabled()
    assert gc.isenabled() is enabled


def test_the_collector_is_set_back_after_an_error(restore_gc):
    gc.enable()
    with pytest.raises(RuntimeError, match="in a member"), collector_paused():
        raise RuntimeError("in a member")
    assert gc.isenabled()
