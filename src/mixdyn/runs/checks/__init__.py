"""Checks of a file's runs, made before anything is computed.

``mixdyn check`` and ``mixdyn run`` plan and check every run first, so each fault below is an
input error (exit 2) naming the file, line and setting, never a failure after minutes of
computing.

When a run is planned (:meth:`.kinds.RunKind.plan`):

* ``options``: only the names the run's analysis takes (close matches suggested), none that
  repeats a setting of the run itself (``rtol``, ``dt``, ``linear_solver``...), every value of
  the right type, finite and in range (``rho_inf`` in [0, 1], ``max_steps`` >= 1...);
* the step: a fixed-step method needs ``dt``, and ``span / dt`` may not exceed ``max_steps``;
* the outputs: figure and animation files of a known type, each written once; columns the
  run's result has (:func:`columns`);
* the laws: every expression law finite at the run's output times;
* a mixed run's unknown forces and prescribed motions paired one to one.

Once every run is planned: motions replayed ``from_run`` cover the replaying run's span
(:func:`check_replays`) and ``output_units`` are units of their kind (:func:`output_units`).

With numbers, on the run's own set-up (:mod:`mixdyn.runs.setup`): every body's mass and
inertia for a dynamic run (:func:`check_masses`), the drivers against the degrees of freedom
(:func:`mobility`) and a mixed run's solvability (:func:`check_solvable`).

One module a job: :mod:`.settings` (a run's options, step and a mixed run's pairing),
:mod:`.outputs` (files, columns, arrows, ``output_units``), :mod:`.laws` (finite and
continuous laws, replayed motions), :mod:`.start` (masses, degrees of freedom, solvability, on
the run's start) and :mod:`.command` (what ``mixdyn check`` checks of the whole file).
"""

from .command import file_warnings, require_size
from .laws import check_laws, check_replays
from .outputs import BODY_COLUMNS, check_column, check_outputs, column_kind, columns, output_units
from .settings import (
    DYNAMIC_OPTIONS,
    INVERSE_OPTIONS,
    RUN_SETTINGS,
    check_mixed,
    check_options,
    check_settings,
    check_step,
    known_options,
)
from .start import check_masses, check_solvable, mobility

__all__ = [
    "BODY_COLUMNS",
    "DYNAMIC_OPTIONS",
    "INVERSE_OPTIONS",
    "RUN_SETTINGS",
    "check_column",
    "check_laws",
    "check_masses",
    "check_mixed",
    "check_options",
    "check_outputs",
    "check_replays",
    "check_settings",
    "check_solvable",
    "check_step",
    "column_kind",
    "columns",
    "file_warnings",
    "known_options",
    "mobility",
    "output_units",
    "require_size",
]
