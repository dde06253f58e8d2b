"""An mkdocs hook: the model-file reference, generated at build time from the file schema.

The model-file format is declared once, as the pydantic classes of ``mixdyn.io.schema``: each
field carries its type, default and description (the string below it). This hook reads the
JSON Schema those classes produce (``mixdyn.io.schema.json_schema()``, what ``mixdyn schema``
prints) and writes, under ``reference/model-file/``:

- ``index.md``: the top-level keys of a model file, and the parts only they use (units,
  ground, bodies, assembly);
- a page per element kind and per run kind: every list of the top level whose items are told
  apart by a key (``joints`` and ``drivers`` by ``type``, ``runs`` by ``kind``...) gets a
  section, with an index page and a page per kind, in the order the schema lists them (the
  element registries' order);
- ``laws.md``: the forms of a law of time;
- ``parts.md``: the parts shared by several kinds (output times, plots, animations...).

A part used by one page only is described on that page. A new element kind registered in the
schema gets its page and its place in the navigation without an edit here. Element pages link
to the element's Python class in the API reference when the package exports it.

It also makes sure the API reference covers the public API: a name of ``mixdyn.__all__``
that no page of ``reference/`` documents (``::: mixdyn.NAME``) is appended to the API
reference's first page, so that a new public name is never missing from the site.
"""

from __future__ import annotations

import importlib
import json
import re
import typing
from pathlib import Path

from mkdocs.structure.files import File

OUT = "reference/model-file"
INDEX = f"{OUT}/index.md"
API_INDEX = "reference/index.md"

_pages: dict[str, str] = {}
_public: list[str] = []


# --------------------------------------------------------------------------- schema
def _schema():
    return importlib.import_module("mixdyn.io.schema")


def _law_classes(s) -> list[str]:
    """Names of the classes of ``LawSpec``'s union (the mapping forms of a law)."""
    names: list[str] = []

    def walk(t):
        if isinstance(t, type):
            names.append(t.__name__)
            return
        for a in typing.get_args(t):
            walk(a)

    walk(getattr(s, "LawSpec", None))
    return names


def _refs(node) -> set[str]:
    """Names of the definitions a JSON Schema node refers to."""
    out: set[str] = set()
    if isinstance(node, dict):
        ref = node.get("$ref")
        if isinstance(ref, str) and ref.startswith("#/$defs/"):
            out.add(ref.rsplit("/", 1)[-1])
        for v in node.values():
            out |= _refs(v)
    elif isinstance(node, list):
        for v in node:
            out |= _refs(v)
    return out


class Reference:
    """The pages of the model-file reference, from one JSON Schema."""

    def __init__(self):
        s = _schema()
        self.s = s
        self.js = s.json_schema()
        self.defs: dict[str, dict] = self.js.get("$defs", {})
        self.laws = [n for n in _law_classes(s) if n in self.defs]
        # Element spec classes -> the model class they build (for links to the API).
        self.element_class: dict[str, str] = {}
        for reg in ("JOINT_SPECS", "DRIVER_SPECS", "FORCE_SPECS"):
            for model_class, spec in getattr(s, reg, {}).items():
                self.element_class[spec.__name__] = model_class
        # page -> its main definitions (a page's own subject, in order)
        self.page_of: dict[str, str] = {}
        self.sections: list[tuple[str, str, list[tuple[str, str]]]] = []
        for key, prop in self.js.get("properties", {}).items():
            items = prop.get("items", {}) if prop.get("type") == "array" else {}
            disc = items.get("discriminator")
            if not disc:
                continue
            tag_of = {v.rsplit("/", 1)[-1]: k for k, v in disc["mapping"].items()}
            order = [r.rsplit("/", 1)[-1] for r in (x.get("$ref", "") for x in items["oneOf"])]
            kinds = []
            for name in order:
                if name in tag_of:
                    page = f"{OUT}/{key}/{tag_of[name]}.md"
                    self.page_of[name] = page
                    kinds.append((tag_of[name], name))
            self.sections.append((key, disc["propertyName"], kinds))
        for name in self.laws:
            self.page_of[name] = f"{OUT}/laws.md"
        self.page_of["__root__"] = INDEX
        # The other definitions: on the one page that uses them, else on parts.md.
        reach: dict[str, set[str]] = {}
        root = {k: v for k, v in self.js.items() if k != "$defs"}
        mains = [("__root__", root)] + [(n, self.defs[n]) for n in self.page_of if n in self.defs]
        for name, node in mains:
            page = self.page_of[name]
            seen: set[str] = set()
            todo = list(_refs(node))
            while todo:
                d = todo.pop()
                if d in seen or d in self.page_of or d not in self.defs:
                    continue
                seen.add(d)
                todo.extend(_refs(self.defs[d]))
            for d in seen:
                reach.setdefault(d, set()).add(page)
        self.extra: dict[str, list[str]] = {}
        for d in self.defs:
            if d in self.page_of:
                continue
            pages = reach.get(d, set())
            page = next(iter(pages)) if len(pages) == 1 else f"{OUT}/parts.md"
            self.page_of[d] = page
            self.extra.setdefault(page, []).append(d)

    # ----------------------------------------------------------------------- rendering
    def anchor(self, name: str) -> str:
        return name.lower()

    def title(self, name: str) -> str:
        for key, _, kinds in self.sections:
            for tag, n in kinds:
                if n == name:
                    return tag
        return name[:-4] if name.endswith("Spec") and len(name) > 4 else name

    def link(self, name: str, here: str) -> str:
        page = self.page_of.get(name)
        if page is None:
            return f"`{name}`"
        kinds = {n for _, _, ks in self.sections for _, n in ks}
        frag = "" if name in kinds else f"#{self.anchor(name)}"
        return f"[{self.title(name)}]({_relative(page, here)}{frag})"

    def type_of(self, node: dict, here: str) -> str:
        """A short description of a JSON Schema node's type, with links."""
        if not isinstance(node, dict) or not node:
            return "any"
        refs_here = {x.get("$ref", "").rsplit("/", 1)[-1] for x in node.get("oneOf", [])}
        refs_here |= {x.get("$ref", "").rsplit("/", 1)[-1] for x in node.get("anyOf", [])}
        if self.laws and set(self.laws) <= refs_here:
            return f"[law]({_relative(f'{OUT}/laws.md', here)})"
        if "$ref" in node:
            return self.link(node["$ref"].rsplit("/", 1)[-1], here)
        if "const" in node:
            return f"`{json.dumps(node['const'])}`"
        if "enum" in node:
            return " \\| ".join(f"`{json.dumps(v)}`" for v in node["enum"])
        for key in ("anyOf", "oneOf"):
            if key in node:
                parts = [x for x in node[key] if x.get("type") != "null"]
                kinds = [x.get("type") for x in parts]
                if kinds == ["number", "string"] and all(len(x) == 1 for x in parts):
                    text = "scalar"
                else:
                    text = " or ".join(dict.fromkeys(self.type_of(x, here) for x in parts))
                if len(parts) < len(node[key]):
                    text += " or null"
                return text
        t = node.get("type")
        if t == "array":
            if "prefixItems" in node:
                return "[" + ", ".join(self.type_of(x, here) for x in node["prefixItems"]) + "]"
            text = f"list of {self.type_of(node.get('items', {}), here)}"
            return text + _bounds(node, "minItems", "maxItems", "items")
        if t == "object":
            add = node.get("additionalProperties")
            if isinstance(add, dict):
                return f"mapping of name to {self.type_of(add, here)}"
            return "mapping"
        if t in ("integer", "number"):
            return t + _bounds(node, "minimum", "maximum", "", "exclusiveMinimum")
        if t == "string":
            return "string" + _bounds(node, "minLength", "maxLength", "characters")
        return t or "any"

    def fields(self, d: dict, here: str, first: str | None = None) -> str:
        props = d.get("properties", {})
        if not props:
            return ""
        if first in props:  # the key that tells the kinds apart, first
            props = {first: props[first], **{k: v for k, v in props.items() if k != first}}
        required = set(d.get("required", []))
        rows = ["| key | type | default | description |", "|---|---|---|---|"]
        for key, p in props.items():
            if key in required:
                default = "required"
            elif "default" in p:
                default = _default(p["default"])
            else:  # a default factory: an empty list or mapping
                default = "empty"
            rows.append(
                f"| `{key}` | {self.type_of(p, here)} | {default} | {_cell(p.get('description', ''))} |"
            )
        return "\n".join(rows)

    def section(self, name: str, here: str, level: int = 2) -> str:
        d = self.defs[name]
        out = [f"{'#' * level} {self.title(name)} {{#{self.anchor(name)}}}", ""]
        if d.get("description"):
            out += [_text(d["description"]), ""]
        out += [self.fields(d, here), ""]
        return "\n".join(out)

    def kind_page(self, key: str, prop_name: str, tag: str, name: str) -> str:
        here = self.page_of[name]
        d = self.defs[name]
        what = key[:-1] if key.endswith("s") else key
        out = [f"# `{tag}` {what}", ""]
        if d.get("description"):
            out += [_text(d["description"]), ""]
        out.append(f"In a model file: an entry of `{key}:` with `{prop_name}: {tag}`.")
        model_class = self.element_class.get(name)
        if model_class:
            if model_class in _public:
                out.append(f"In Python: [`mixdyn.{model_class}`][mixdyn.{model_class}].")
            else:
                out.append(f"In Python: `mixdyn.model.{model_class}`.")
        out += ["", self.fields(d, here, first=prop_name), ""]
        for extra in self.extra.get(here, []):
            out.append(self.section(extra, here))
        return "\n".join(out)

    def section_index(self, key: str, prop_name: str, kinds) -> str:
        here = f"{OUT}/{key}/index.md"
        out = [f"# {key.capitalize()}", ""]
        out += [
            f"Each entry of `{key}:` is one of the kinds below, told apart by its "
            f"`{prop_name}` key.",
            "",
            f"| `{prop_name}` | description |",
            "|---|---|",
        ]
        for tag, name in kinds:
            first = _first_sentence(self.defs[name].get("description", ""))
            out.append(f"| [`{tag}`]({_relative(self.page_of[name], here)}) | {_cell(first)} |")
        return "\n".join(out) + "\n"

    def index_page(self) -> str:
        here = INDEX
        out = [
            "# Model-file reference",
            "",
            "Generated from the file schema (`mixdyn.io.schema`; `mixdyn schema` prints it as",
            "JSON Schema, with the same descriptions). The guide to the format, with",
            "examples, is [Model files](../../model-files.md). Every number without a unit is",
            "in the model's units; a *scalar* is a number or a string with a unit or a",
            "constant expression (`\"500 N*mm\"`, `\"30 deg\"`, `\"pi/6\"`).",
            "",
        ]
        if self.js.get("description"):
            out += [_text(self.js["description"]), ""]
        out += ["## Top-level keys", "", self.fields(self.js, here), ""]
        for key, prop_name, kinds in self.sections:
            out.append(
                f"`{key}` entries: "
                + ", ".join(f"[`{tag}`]({_relative(self.page_of[n], here)})" for tag, n in kinds)
                + "."
            )
            out.append("")
        for extra in self.extra.get(here, []):
            out.append(self.section(extra, here))
        return "\n".join(out)

    def laws_page(self) -> str:
        here = f"{OUT}/laws.md"
        out = [
            "# Laws",
            "",
            "A law (a driver's motion, a force's magnitude) is a scalar — a number or quantity",
            "(constant) or an expression string of `t` in the model's time unit",
            "(`10*sin(pi*t/2)`) — or a mapping with exactly one of the keys below. Force",
            "magnitudes may also use body states (`-c*wheel.omega`). The functions allowed in",
            "expressions are listed in [Model files](../../model-files.md).",
            "",
        ]
        for name in self.laws:
            out.append(self.section(name, here))
        for extra in self.extra.get(here, []):
            out.append(self.section(extra, here, level=3))
        return "\n".join(out)

    def parts_page(self) -> str:
        here = f"{OUT}/parts.md"
        out = ["# Common parts", "", "Parts of a model file used by several kinds.", ""]
        for extra in self.extra.get(here, []):
            out.append(self.section(extra, here))
        return "\n".join(out)

    def pages(self) -> dict[str, str]:
        pages = {INDEX: self.index_page(), f"{OUT}/laws.md": self.laws_page()}
        if self.extra.get(f"{OUT}/parts.md"):
            pages[f"{OUT}/parts.md"] = self.parts_page()
        for key, prop_name, kinds in self.sections:
            pages[f"{OUT}/{key}/index.md"] = self.section_index(key, prop_name, kinds)
            for tag, name in kinds:
                pages[self.page_of[name]] = self.kind_page(key, prop_name, tag, name)
        return pages

    def nav(self) -> list:
        nav: list = [INDEX]
        for key, _, kinds in self.sections:
            nav.append(
                {key.capitalize(): [f"{OUT}/{key}/index.md"]
                 + [{tag: self.page_of[n]} for tag, n in kinds]}
            )
        nav.append({"Laws": f"{OUT}/laws.md"})
        if self.extra.get(f"{OUT}/parts.md"):
            nav.append({"Common parts": f"{OUT}/parts.md"})
        return nav


# --------------------------------------------------------------------------- text helpers
def _relative(target: str, here: str) -> str:
    t, h = target.split("/"), here.split("/")[:-1]
    i = 0
    while i < min(len(t) - 1, len(h)) and t[i] == h[i]:
        i += 1
    return "/".join([".."] * (len(h) - i) + t[i:])


def _text(s: str) -> str:
    """A description as Markdown: one paragraph per blank-line-separated block."""
    return "\n\n".join(" ".join(p.split()) for p in re.split(r"\n\s*\n", s.strip()))


def _cell(s: str) -> str:
    return " ".join(s.split()).replace("\n", " ")


def _first_sentence(s: str) -> str:
    s = " ".join(s.split())
    m = re.search(r"(?<=[a-z0-9`)\]])\.(\s|$)", s)
    return s[: m.start() + 1] if m else s


def _default(v) -> str:
    if v is None:
        return "none"
    if v == {} or v == []:
        return "empty"
    return f"`{json.dumps(v, ensure_ascii=False)}`"


def _bounds(node: dict, lo: str, hi: str, unit: str = "", xlo: str = "") -> str:
    parts = []
    if xlo and xlo in node:
        parts.append(f"> {node[xlo]:g}" if isinstance(node[xlo], float) else f"> {node[xlo]}")
    if lo in node:
        parts.append(f"≥ {node[lo]}")
    if hi in node:
        parts.append(f"≤ {node[hi]}")
    if not parts:
        return ""
    return " (" + ", ".join(parts) + (f" {unit}" if unit else "") + ")"


# --------------------------------------------------------------------------- public API
def _public_names() -> list[str]:
    mixdyn = importlib.import_module("mixdyn")
    return [n for n in getattr(mixdyn, "__all__", []) if not n.startswith("_")]


def _documented(docs_dir: Path) -> set[str]:
    names: set[str] = set()
    for md in (docs_dir / "reference").rglob("*.md"):
        names |= set(re.findall(r"^::: mixdyn\.(\w+)", md.read_text(encoding="utf-8"), re.M))
    return names


# --------------------------------------------------------------------------- mkdocs events
def on_config(config, **kwargs):
    global _pages, _public
    _public = _public_names()
    ref = Reference()
    _pages = ref.pages()

    def place(nav):
        for i, item in enumerate(nav):
            if isinstance(item, dict):
                for title, value in item.items():
                    if value == INDEX:
                        nav[i] = {title: ref.nav()}
                        return True
                    if isinstance(value, list) and place(value):
                        return True
        return False

    if config.get("nav") is not None and not place(config["nav"]):
        raise ValueError(f"mkdocs.yml: the nav names no {INDEX} for the model-file reference")
    return config


def on_files(files, config, **kwargs):
    for path, content in _pages.items():
        files.append(File.generated(config, path, content=content))
    return files


def on_page_markdown(markdown, page, config, **kwargs):
    if page.file.src_uri != API_INDEX:
        return markdown
    errors = importlib.import_module("mixdyn.errors")
    documented = _documented(Path(config["docs_dir"]))
    missing = [
        n
        for n in _public
        if n not in documented
        and n != "errors"
        and not (isinstance(getattr(errors, n, None), type))  # documented on the errors page
    ]
    if not missing:
        return markdown
    extra = "\n\n## Other names\n\n" + "\n\n".join(f"::: mixdyn.{n}" for n in missing) + "\n"
    return markdown + extra
