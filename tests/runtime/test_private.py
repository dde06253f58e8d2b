"""The private hooks (``mixdyn.runtime._private``): used only on checked versions, with a
public fallback that computes the same numbers; nothing of JAX or diffrax is left changed
for a user's own code after ``import mixdyn`` and after a run."""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import textwrap

import equinox.internal as eqxi
import numpy as np
import pytest

import mixdyn as md
from fixtures import pendulum
from mixdyn.runtime import _private


def test_hooks_run_only_on_checked_versions(monkeypatch):
    monkeypatch.delenv(_private.PUBLIC_ONLY_ENV, raising=False)
    first, after = _private.KNOWN["diffrax"]
    assert _private.allowed("diffrax", first)
    assert not _private.allowed("diffrax", after)
    assert not _private.allowed("diffrax", (0, 4, 30))
    monkeypatch.setenv(_private.PUBLIC_ONLY_ENV, "1")
    assert not _private.allowed("diffrax", first)


def test_public_only_names_hooks_one_by_one(monkeypatch):
    """``$MIXDYN_PUBLIC_ONLY`` given hook names sends those hooks, and only those, to
    their public paths; an unknown word means every hook, as ``1`` does."""
    first, _ = _private.KNOWN["diffrax"]
    monkeypatch.setenv(_private.PUBLIC_ONLY_ENV, "roomy, exit_now")
    assert not _private.allowed("diffrax", first, hook="roomy")
    assert _private.allowed("diffrax", first, hook="chained_floor")
    assert _private.allowed("diffrax", first)  # no hook named: the version check alone
    monkeypatch.setenv(_private.PUBLIC_ONLY_ENV, "yes")
    assert all(_private.public_only(hook) for hook in _private.HOOKS)
    monkeypatch.setenv(_private.PUBLIC_ONLY_ENV, "0")
    assert not any(_private.public_only(hook) for hook in _private.HOOKS)


def test_diffrax_is_given_back_after_a_run():
    """The chained floor is diffrax's only while mixdyn traces one of its own solves."""
    from diffrax import _integrate

    assert _integrate.eqxi is eqxi
    seen = []
    with _private.chained_floor():
        seen.append(_integrate.eqxi)
        with _private.chained_floor():  # nested (another thread tracing): still swapped
            seen.append(_integrate.eqxi)
        seen.append(_integrate.eqxi)
    assert _integrate.eqxi is eqxi
    if _private.allowed("diffrax"):
        assert all(type(x).__name__ == "Internal" for x in seen)
    model = pendulum(theta0=0.3)
    md.forward(model, np.linspace(0.0, 0.2, 5), method="projection", rtol=1e-8, atol=1e-8)
    assert _integrate.eqxi is eqxi


def test_the_public_path_does_not_swap(monkeypatch):
    from diffrax import _integrate

    monkeypatch.setenv(_private.PUBLIC_ONLY_ENV, "1")
    with _private.chained_floor():
        assert _integrate.eqxi is eqxi


USER_SCRIPT = textwrap.dedent(
    """
    import json, sys
    import jax, diffrax, equinox.internal
    from jax._src import lru_cache
    put = lru_cache.LRUCache.put
    before = (jax.config.jax_compilation_cache_dir, jax.config.jax_enable_compilation_cache)
    import numpy as np
    import mixdyn as md
    sys.path.insert(0, sys.argv[1])
    from fixtures import pendulum
    model = pendulum(theta0=0.3)
    r = md.forward(model, np.linspace(0.0, 0.5, 6), method="projection", rtol=1e-10, atol=1e-10)
    after = (jax.config.jax_compilation_cache_dir, jax.config.jax_enable_compilation_cache)
    from diffrax import _integrate
    print(json.dumps({
        "jax_cache": [before, after],
        "diffrax": _integrate.eqxi is equinox.internal,
        "lru_put": lru_cache.LRUCache.put is put,
        "phi": r["bob.phi"].tolist(),
        "omega": r["bob.omega"].tolist(),
        "folder": md.runtime.cache_folder(),
    }))
    """
)


def _user(tmp_path, **env) -> dict:
    script = tmp_path / "user.py"
    script.write_text(USER_SCRIPT)
    tests = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    full = dict(os.environ, MIXDYN_CACHE_DIR=str(tmp_path / "cache"), **env)
    full.pop("MIXDYN_NO_CACHE", None)
    full.pop("JAX_COMPILATION_CACHE_DIR", None)
    out = subprocess.run(
        [sys.executable, str(script), tests],
        env=full,
        capture_output=True,
        text=True,
        timeout=600,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.timeout(900)
def test_a_users_jax_and_diffrax_are_left_as_they_were_and_both_paths_agree(tmp_path):
    """A program that imports mixdyn and runs it finds JAX's compilation cache as it set it
    (off), diffrax's globals and JAX's cache class unchanged; the public path (every hook
    off) gives the private path's numbers, bit for bit."""
    hooked = _user(tmp_path)
    public = _user(tmp_path, MIXDYN_PUBLIC_ONLY="1")
    for got in (hooked, public):
        assert got["jax_cache"][0] == got["jax_cache"][1]
        assert got["jax_cache"][1][0] is None
        assert got["diffrax"] and got["lru_put"]
        assert got["folder"] == str(tmp_path / "cache")
    assert hooked["phi"] == public["phi"]
    assert hooked["omega"] == public["omega"]
    assert abs(hooked["phi"][0] - 0.3) < 1e-12


def test_a_gif_is_the_same_picture_with_the_shared_palette_and_pillow_is_given_back(tmp_path):
    """The figure worker's GIFs are written with Pillow keeping their one palette: every
    decoded frame equals the one Pillow writes on its own (public path), Pillow's function is
    its own again afterwards, and outside the worker nothing is swapped."""
    from PIL import GifImagePlugin, Image

    from mixdyn.viz import _draw

    assert _draw.GIF_CONTEXT is contextlib.nullcontext  # a user's process: Pillow as it is
    own = GifImagePlugin._get_optimize
    from mixdyn.viz.animate import movie_data

    model = pendulum(theta0=0.3)
    t = np.linspace(0.0, 1.0, 12)
    q = np.repeat(np.asarray(model.q0, dtype=float)[None, :], t.size, axis=0)
    q[:, 2] += 0.5 * t  # the bar turns
    data = movie_data(model=model, t=t, q=q, frames=12)
    frames = {}
    for name, context in (("public", contextlib.nullcontext), ("hook", _private.shared_palette)):
        _draw.GIF_CONTEXT = context
        try:
            path = _draw.movie(data, tmp_path / f"{name}.gif", fps=10)
        finally:
            _draw.GIF_CONTEXT = contextlib.nullcontext
        with Image.open(path) as im:
            frames[name] = [np.asarray(f.convert("RGB")) for f in _frames(im)]
        assert GifImagePlugin._get_optimize is own
    with _private.shared_palette():  # on this Pillow, swapped only within
        swapped = GifImagePlugin._get_optimize
    assert swapped is (_private._keep_palette if _private.allowed("pillow") else own)
    assert GifImagePlugin._get_optimize is own
    assert len(frames["hook"]) == len(frames["public"]) > 1
    for a, b in zip(frames["hook"], frames["public"], strict=True):
        np.testing.assert_array_equal(a, b)


def _frames(im):
    from PIL import ImageSequence

    return [f.copy() for f in ImageSequence.Iterator(im)]
