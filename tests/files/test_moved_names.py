"""Names that moved up a layer keep their old spelling with a DeprecationWarning:
``mixdyn.io.Runner``, ``Plan`` and ``execute`` are :mod:`mixdyn.runs`' objects, and the file
formats (``mixdyn.io``) do not import the runs of a file to offer them."""

import subprocess
import sys
import warnings

import pytest

import mixdyn.io as mio
import mixdyn.runs


@pytest.mark.parametrize("name", ["Runner", "Plan", "execute"])
def test_an_old_spelling_is_the_new_object_with_a_warning(name):
    with pytest.warns(DeprecationWarning, match=rf"mixdyn\.io\.{name} is deprecated: use "
                      rf"mixdyn\.runs\.{name}"):  # fmt: skip
        old = getattr(mio, name)
    assert old is getattr(mixdyn.runs, name)
    assert name not in mio.__all__


def test_other_names_are_not_found():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(AttributeError, match=r"'mixdyn\.io' has no attribute 'Runer'"):
            mio.Runer  # noqa: B018


def test_the_file_formats_do_not_import_the_runs():
    """A fresh ``import mixdyn.io`` leaves :mod:`mixdyn.runs` unloaded until an old
    spelling asks for it."""
    code = (
        "import sys, warnings; import mixdyn.io as mio; "
        "before = 'mixdyn.runs' in sys.modules; "
        "warnings.simplefilter('ignore'); mio.execute; "
        "print(before, 'mixdyn.runs' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "True"]
