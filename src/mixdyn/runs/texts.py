"""The texts the ``mixdyn`` command prints or writes: a model file in normal form (``mixdyn
dump``: :func:`normal_form`) and the JSON Schema of model files (``mixdyn schema``:
:func:`schema_text`), written to a checked path (:func:`write_text`).

Example::

    write_text(pathlib.Path("four_bar.yaml"), normal_form("examples/four_bar.yaml"))
"""

from __future__ import annotations

import pathlib


def normal_form(file, output: pathlib.Path | None = None) -> str:
    """A model file read, validated and built, then written back in normal form (defaults
    left out), keeping its comments, key order and flow style where its keys remain: loading
    it gives the same model.

    Args:
        file: the model file.
        output: where the text is to be written (checked first), or None.
    """
    from ..io import build, read
    from ..io.dump import dumps_keeping
    from .checks import require_size
    from .outputs import check_output

    if output is not None:
        check_output(output, "--output")
    spec = read(file)
    require_size(spec, file)
    build(spec)
    return dumps_keeping(pathlib.Path(file).read_text(encoding="utf-8"), spec)


def schema_text() -> str:
    """The JSON Schema of model files (:func:`mixdyn.io.json_schema`), indented."""
    import json

    from ..io import json_schema

    return json.dumps(json_schema(), indent=2)


def write_text(path: pathlib.Path, text: str) -> None:
    """Write ``text`` to ``path`` (its folder created), after
    :func:`~.outputs.check_output`."""
    from .outputs import check_output

    check_output(path, "--output")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")


__all__ = ["normal_form", "schema_text", "write_text"]
