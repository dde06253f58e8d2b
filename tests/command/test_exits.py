"""How the command ends on each error (:func:`mixdyn.runs.exits.exit_for`): the exit codes
and lines its documentation promises (2 and ``FILE: ...; what to do`` for bad input, 1 and
the run, time and cause for a numerical failure, 130 for an interrupt), and which errors
escape as they are."""

import pytest

from mixdyn.errors import AssemblyError, SingularityError
from mixdyn.io import FileError
from mixdyn.runs.exits import EXIT_INPUT, EXIT_NUMERICAL, exit_for


def test_input_errors_exit_2_naming_the_file_and_what_to_do():
    error = FileError("no run 'x'", "--run", file="m.yaml", line=3, hint="runs: a, b")
    assert exit_for(error, "other.yaml") == (EXIT_INPUT, "m.yaml:3: --run: no run 'x'; runs: a, b")
    code, line = exit_for(AssemblyError("no start closes the joints"), "m.yaml")
    assert code == EXIT_INPUT and line.startswith("m.yaml: the start cannot be assembled: ")
    assert exit_for(RecursionError(), None)[0] == EXIT_INPUT
    missing = FileNotFoundError(2, "No such file or directory", "out/x.csv")
    assert exit_for(missing, "m.yaml") == (
        EXIT_INPUT,
        "out/x.csv: No such file or directory; check the path and its permissions",
    )


def test_a_numerical_failure_exits_1_with_its_run_and_cause():
    error = SingularityError("the mass matrix is singular", time=0.25)
    error.run = "forward"
    code, line = exit_for(error, "m.yaml")
    assert code == EXIT_NUMERICAL
    assert line.startswith("m.yaml: run 'forward': numerical failure (SingularityError): ")
    assert line.endswith("at t = 0.25: the mass matrix is singular")


def test_an_interrupt_exits_130_and_a_bug_asks_for_a_report(monkeypatch):
    assert exit_for(KeyboardInterrupt(), None) == (130, "mixdyn: interrupted")
    monkeypatch.delenv("MIXDYN_DEBUG", raising=False)
    code, line = exit_for(ZeroDivisionError("x"), "m.yaml")
    assert code == EXIT_NUMERICAL and "please report it" in line


@pytest.mark.parametrize("error", [SystemExit(3), ZeroDivisionError("x")])
def test_an_exit_of_its_own_and_a_bug_under_debug_escape(monkeypatch, error):
    monkeypatch.setenv("MIXDYN_DEBUG", "1")
    assert exit_for(error, "m.yaml") is None
