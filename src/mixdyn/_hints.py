"""Hints for a misspelled name: the close matches among the known names, not all of them."""

from __future__ import annotations

import difflib
from collections.abc import Iterable

#: How many known names a hint lists when none is close.
LISTED = 8


def did_you_mean(name: str, known: Iterable[str], what: str = "columns") -> str:
    """A hint for ``name``, which is not among ``known``: ``"did you mean 'slider.x'?"`` for
    close spellings (difflib, and names differing only in case), else the first
    :data:`LISTED` known names and how many there are."""
    known = [str(k) for k in known]
    lower = {k.lower(): k for k in known}
    close = difflib.get_close_matches(str(name), known, n=3, cutoff=0.6)
    same = lower.get(str(name).lower())
    if same is not None:  # the name in another case first
        close = [same] + [c for c in close if c != same]
    if close:
        return "did you mean " + " or ".join(map(repr, close[:3])) + "?"
    head = ", ".join(known[:LISTED])
    if len(known) > LISTED:
        return f"the {what} are {head}, ... ({len(known)} in all)"
    return f"the {what} are {head}"


def count(n: int, noun: str, plural: str | None = None) -> str:
    """``n`` with its noun in the number it takes: ``count(1, "driver")`` -> ``"1 driver"``,
    ``count(3, "body", "bodies")`` -> ``"3 bodies"`` (``plural`` default: ``noun + "s"``)."""
    return f"{n:,} {noun if n == 1 else (plural or noun + 's')}"


def listed(names: Iterable[str], noun: str, plural: str | None = None) -> str:
    """A noun and the names it introduces, in the number they take: ``listed(["motor"],
    "driver")`` -> ``"driver motor"``, two names -> ``"drivers a, b"``."""
    names = [str(n) for n in names]
    return f"{noun if len(names) == 1 else (plural or noun + 's')} {', '.join(names)}"
