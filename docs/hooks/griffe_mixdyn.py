"""griffe extensions for mixdyn's API reference (loaded by mkdocstrings, see mkdocs.yml).

``PublicNames``: ``mixdyn.analysis`` imports each analysis function from the module of the
same name (``from .kinematic import kinematic``). At run time the name is the function; griffe,
reading the source, keeps the submodule under that name, so ``::: mixdyn.kinematic`` would
document the module. After the package is loaded, every top-level alias of ``mixdyn`` whose
target is a module holding a member of the alias's own name is pointed at that member, as
Python resolves it.

``SphinxRoles``: mixdyn's docstrings cross-reference with Sphinx roles (``:class:`~mixdyn.UnitSystem```,
``:func:`set_cache```) and end some lines with ``::`` before a literal block. Markdown shows
those literally, so this extension rewrites them before mkdocstrings renders a docstring:

- a role naming a public object of the package (``mixdyn.X`` with ``X`` in
  ``mixdyn.__all__``, or ``mixdyn.errors.X``) becomes an autorefs link to its entry in the
  API reference;
- any other role (private modules, relative names, methods) becomes a code span of the name
  (the last component where the role asks for it with ``~``);
- a line ending in ``::`` ends in ``:``.

The docstrings in ``src/`` stay as they are; only the rendered text changes.
"""

from __future__ import annotations

import ast
import pathlib
import re

from griffe import Extension

_ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|data|attr|exc|obj|const):`(~?)([^`<>]+?)`")
_LITERAL = re.compile(r"(?<=\S)::$", re.MULTILINE)


def _all(path: pathlib.Path) -> set[str]:
    """The names in a module's ``__all__`` list, read from its source."""
    names: set[str] = set()
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if (
            isinstance(node, ast.Assign)
            and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets)
            and isinstance(node.value, ast.List)
        ):
            names |= {e.value for e in node.value.elts if isinstance(e, ast.Constant)}
    return {n for n in names if not n.startswith("_")}


def _public_names() -> set[str]:
    """The names in ``mixdyn.__all__`` and ``mixdyn.model.__all__`` (read from the source,
    without importing the package), those of the public modules ``mixdyn.analyses`` and
    ``mixdyn.paths``, and the public classes of ``mixdyn.errors``."""
    src = pathlib.Path(__file__).resolve().parents[2] / "src" / "mixdyn"
    names = _all(src / "__init__.py") | _all(src / "model" / "__init__.py")
    public = {f"mixdyn.{n}" for n in names}
    for module in ("analyses", "paths"):
        if (src / f"{module}.py").exists():
            public |= {f"mixdyn.{module}.{n}" for n in _all(src / f"{module}.py")}
    errors = ast.parse((src / "errors.py").read_text(encoding="utf-8"))
    error_names = {n.name for n in errors.body if isinstance(n, ast.ClassDef)}
    return public | {f"mixdyn.errors.{n}" for n in error_names if not n.startswith("_")} | {
        "mixdyn.errors"
    }


class SphinxRoles(Extension):
    """Rewrite Sphinx roles and ``::`` of every docstring (see the module's docstring)."""

    def __init__(self) -> None:
        super().__init__()
        self.public = _public_names()

    def _role(self, m: re.Match) -> str:
        short, target = m.group(1), m.group(2).strip()
        shown = target.rsplit(".", 1)[-1] if short else target
        if target in self.public:
            return f"[`{shown}`][{target}]"
        return f"`{shown}`"

    def on_instance(self, *, obj, **kwargs) -> None:
        doc = getattr(obj, "docstring", None)
        if doc is None or not doc.value:
            return
        text = _ROLE.sub(self._role, doc.value)
        doc.value = _LITERAL.sub(":", text)


class PublicNames(Extension):
    """Point ``mixdyn.NAME`` at the object Python finds there (see the module's docstring)."""

    def on_package(self, *, pkg, **kwargs) -> None:
        if pkg.name != "mixdyn":
            return
        for name, member in list(pkg.members.items()):
            if not member.is_alias:
                continue
            try:
                target = member.final_target
            except Exception:  # an alias griffe cannot resolve: left as it is
                continue
            if target.is_module and name in target.members:
                member.target = target.members[name]
