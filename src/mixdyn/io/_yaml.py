"""Safe YAML reading that keeps the line of every value and refuses aliases.

The text is composed into YAML nodes by PyYAML's safe loader (no Python tags, no code), then
turned into plain data by hand so that

* anchors and aliases are refused (no "billion laughs" expansion),
* duplicate keys in a mapping are refused (YAML would silently keep the last one),
* the line of every value is recorded under its path, e.g. ``("joints", 2, "point_i")``.
"""

from __future__ import annotations

import re

import yaml

#: Largest model file read [bytes] (20 MB): a mechanism of 10,000 links takes 2 MB.
MAX_BYTES = 20_000_000
#: Deepest nesting of mappings and sequences accepted.
MAX_DEPTH = 40

Path = tuple[str | int, ...]


class YamlError(ValueError):
    """The text is not acceptable YAML. Attributes: ``line`` (1-based or None), ``problem``,
    ``hint``."""

    def __init__(self, problem: str, line: int | None = None, hint: str = ""):
        self.problem = problem
        self.line = line
        self.hint = hint
        super().__init__(problem)


class _RefuseAliases:
    """A composer mixin that refuses anchors and aliases."""

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            raise YamlError(
                f"YAML alias '*{event.anchor}' is not allowed",
                event.start_mark.line + 1,
                "write the value out in full; model files do not use anchors or aliases",
            )
        event = self.peek_event()
        anchor = getattr(event, "anchor", None)
        if anchor is not None:
            raise YamlError(
                f"YAML anchor '&{anchor}' is not allowed",
                event.start_mark.line + 1,
                "remove the anchor; model files do not use anchors or aliases",
            )
        return super().compose_node(parent, index)


class _Loader(_RefuseAliases, yaml.SafeLoader):
    """Safe pure-Python loader whose composer refuses anchors and aliases."""


if getattr(yaml, "__with_libyaml__", False):
    from yaml._yaml import CParser
    from yaml.composer import Composer
    from yaml.constructor import SafeConstructor
    from yaml.resolver import Resolver

    class _FastLoader(_RefuseAliases, Composer, CParser, SafeConstructor, Resolver):
        """libyaml's parser (events, in C: ~4x faster) under the Python composer, so that
        anchors and aliases are still refused."""

        def __init__(self, stream):
            CParser.__init__(self, stream)
            SafeConstructor.__init__(self)
            Resolver.__init__(self)
            Composer.__init__(self)

    _LOADERS: tuple = (_FastLoader, _Loader)
else:  # pragma: no cover - PyYAML without libyaml
    _LOADERS = (_Loader,)

# YAML 1.1 reads 1e-8 as a string; accept the exponent forms YAML 1.2 reads as numbers.
for _cls in _LOADERS:
    _cls.add_implicit_resolver(
        "tag:yaml.org,2002:float",
        re.compile(
            r"""^(?:[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?(?:[eE][-+]?[0-9]+)
            |[-+]?\.[0-9_]+(?:[eE][-+]?[0-9]+)?)$""",
            re.X,
        ),
        list("-+0123456789."),
    )

#: Characters YAML does not allow in a stream (control characters, non-characters).
_NOT_PRINTABLE = re.compile("[^\t\n\r\x20-\x7e\x85\xa0-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def _check_text(text: str) -> None:
    """Refuse a text that is too large or holds a character YAML does not allow."""
    if len(text) > MAX_BYTES:
        raise YamlError(
            f"the file is larger than the limit of {MAX_BYTES // 1_000_000} MB",
            None,
            "a model file should hold a description, not data",
        )
    bad = _NOT_PRINTABLE.search(text)
    if bad is not None:
        line = text.count("\n", 0, bad.start()) + 1
        column = bad.start() - (text.rfind("\n", 0, bad.start()) + 1) + 1
        raise YamlError(
            f"control character U+{ord(bad.group()):04X} at column {column} is not allowed",
            line,
            "remove it (a binary or corrupted file?); a model file is plain UTF-8 text",
        )


def _line(node) -> int:
    return node.start_mark.line + 1


def read_yaml(text: str) -> tuple[object, dict[Path, int]]:
    """Parse ``text`` to plain data (dicts, lists, str, int, float, bool, None).

    Returns:
        ``(data, lines)``: the data and the 1-based line of every value by its path.

    Raises:
        YamlError: bad syntax, aliases or anchors, duplicate keys, non-string keys, tags,
            too large or too deeply nested.
    """
    _check_text(text)
    loader = _LOADERS[0](text)
    try:
        return _read_events(loader)
    except Exception:  # any fault: read again below, where it is reported
        pass
    finally:
        loader.dispose()
    return _read_composed(text)


class _RefusedError(Exception):
    """The event reader met something that the composing reader reports (or refuses)."""


def _read_events(loader) -> tuple[object, dict[Path, int]]:
    """Plain data and lines straight from the parser's events, without a node tree.

    The same result as :func:`_read_composed` for every text that it accepts (about 4x
    faster: no nodes, scalars resolved once per distinct value); anything it would refuse
    (an alias, an anchor, a tag, a duplicate or non-name key, depth, a bad value, a syntax
    error, a second document) raises, and the caller reads the text again with
    :func:`_read_composed`, which reports the fault as before.
    """
    get = loader.get_event
    resolve = loader.resolve
    constructors = loader.yaml_constructors
    known: dict[tuple, object] = {}

    def scalar(ev):
        tag = ev.tag
        key = (tag, ev.value, ev.implicit)
        try:
            return known[key]
        except KeyError:
            pass
        if tag is None or tag == "!":
            tag = resolve(yaml.ScalarNode, ev.value, ev.implicit)
        if tag not in _SAFE_TAGS:
            raise _RefusedError(tag)
        if tag == _STR:
            value = ev.value
        else:
            node = yaml.ScalarNode(tag, ev.value, ev.start_mark, ev.end_mark, style=ev.style)
            value = constructors[tag](loader, node)
        known[key] = value
        return value

    lines: dict[Path, int] = {}
    get()  # stream start
    ev = get()
    if type(ev) is yaml.StreamEndEvent:
        return None, lines
    ev = get()  # after the document start: the root node
    # open collections: [container, path, depth, key] (key: _NO_KEY while a mapping awaits
    # its next key; None for a sequence)
    stack: list[list] = []
    root = None
    while True:
        t = type(ev)
        if t is yaml.SequenceEndEvent or t is yaml.MappingEndEvent:
            stack.pop()
            if not stack:
                break
            ev = get()
            continue
        if t is yaml.AliasEvent or ev.anchor is not None:
            raise _RefusedError("alias or anchor")
        if stack:
            frame = stack[-1]
            container, parent, depth, key = frame
            if key is _NO_KEY:
                if t is not yaml.ScalarEvent:
                    raise _RefusedError("key")
                key = scalar(ev)
                if not isinstance(key, str):
                    if isinstance(key, int | float) and not isinstance(key, bool):
                        key = str(key)
                    else:
                        raise _RefusedError("key")
                if key in container:
                    raise _RefusedError("duplicate key")
                frame[3] = key
                ev = get()
                continue
            if key is None:
                path = (*parent, len(container))
            else:
                path = (*parent, key)
                frame[3] = _NO_KEY
            depth += 1
        else:
            path, depth, container, key = (), 0, None, None
        if depth > MAX_DEPTH:
            raise _RefusedError("depth")
        lines[path] = ev.start_mark.line + 1
        if t is yaml.ScalarEvent:
            value = scalar(ev)
        else:
            tag = ev.tag
            mapping = t is yaml.MappingStartEvent
            node_type = yaml.MappingNode if mapping else yaml.SequenceNode
            if tag is None or tag == "!":
                tag = resolve(node_type, None, ev.implicit)
            if tag != (_MAP if mapping else _SEQ):
                raise _RefusedError(tag)
            value = {} if mapping else []
        if container is None:
            root = value
        elif key is None:
            container.append(value)
        else:
            container[key] = value
        if t is not yaml.ScalarEvent:
            stack.append([value, path, depth, _NO_KEY if mapping else None])
        elif not stack:
            break
        ev = get()
    if type(get()) is not yaml.DocumentEndEvent or type(get()) is not yaml.StreamEndEvent:
        raise _RefusedError("more than one document")
    return root, lines


_NO_KEY = object()


def _read_composed(text: str) -> tuple[object, dict[Path, int]]:
    """:func:`read_yaml` through the composer's node tree (the reference; reports faults)."""
    loader = _LOADERS[0](text)
    try:
        try:
            node = loader.get_single_node()
        except yaml.MarkedYAMLError as e:
            mark = e.problem_mark or e.context_mark
            raise YamlError(
                f"YAML syntax error: {e.problem or e.context}",
                mark.line + 1 if mark else None,
                "check the indentation, colons and quotes near that line",
            ) from None
        except yaml.YAMLError as e:
            raise YamlError(f"YAML error: {e}", None, "check the file's syntax") from None
        except RecursionError:
            raise YamlError(
                "the YAML is nested too deeply", None, "flatten the structure"
            ) from None
        lines: dict[Path, int] = {}
        if node is None:
            return None, lines
        data = _to_data(loader, node, (), lines, 0)
        return data, lines
    finally:
        loader.dispose()


def _to_data(loader, node, path: Path, lines: dict, depth: int):
    if depth > MAX_DEPTH:
        raise YamlError(
            f"the YAML is nested more than {MAX_DEPTH} levels deep",
            _line(node),
            "flatten the structure",
        )
    lines[path] = _line(node)
    expected = {yaml.MappingNode: _MAP, yaml.SequenceNode: _SEQ}.get(type(node))
    if expected is not None and node.tag != expected:
        raise YamlError(
            f"YAML tag {node.tag!r} is not allowed",
            _line(node),
            "write plain mappings, lists, numbers and strings",
        )
    if isinstance(node, yaml.MappingNode):
        out = {}
        for key_node, value_node in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                raise YamlError(
                    "YAML merge keys ('<<') are not allowed",
                    _line(key_node),
                    "write the keys out in full",
                )
            if not isinstance(key_node, yaml.ScalarNode):
                raise YamlError(
                    "a mapping key must be a plain name", _line(key_node), "use a plain name"
                )
            key = _scalar(loader, key_node)
            if not isinstance(key, str):
                key = (
                    str(key) if isinstance(key, int | float) and not isinstance(key, bool) else key
                )
            if not isinstance(key, str):
                raise YamlError(
                    f"mapping key {key!r} is not a name", _line(key_node), "quote the key"
                )
            if key in out:
                raise YamlError(
                    f"duplicate key {key!r}",
                    _line(key_node),
                    "every key of a mapping must be unique; remove or rename one",
                )
            out[key] = _to_data(loader, value_node, (*path, key), lines, depth + 1)
        return out
    if isinstance(node, yaml.SequenceNode):
        return [
            _to_data(loader, item, (*path, i), lines, depth + 1)
            for i, item in enumerate(node.value)
        ]
    return _scalar(loader, node)


_MAP = "tag:yaml.org,2002:map"
_STR = "tag:yaml.org,2002:str"
_SEQ = "tag:yaml.org,2002:seq"
_SAFE_TAGS = {
    "tag:yaml.org,2002:str",
    "tag:yaml.org,2002:int",
    "tag:yaml.org,2002:float",
    "tag:yaml.org,2002:bool",
    "tag:yaml.org,2002:null",
}


def _scalar(loader, node):
    if node.tag not in _SAFE_TAGS:
        raise YamlError(
            f"YAML tag {node.tag!r} is not allowed",
            _line(node),
            "write plain numbers and strings (quote the value)",
        )
    try:
        return loader.yaml_constructors[node.tag](loader, node)
    except (yaml.YAMLError, ValueError, OverflowError, IndexError) as e:
        raise YamlError(f"bad value: {e}", _line(node), "quote the value") from None


def line_of(lines: dict[Path, int], path: Path) -> int | None:
    """The line of ``path`` or of its nearest ancestor recorded in ``lines``."""
    path = tuple(path)
    while True:
        if path in lines:
            return lines[path]
        if not path:
            return None
        path = path[:-1]


#: The sections of a model file whose items are named elements, and what one is called.
_SECTIONS = {
    "bodies": "body",
    "joints": "joint",
    "drivers": "driver",
    "forces": "force",
    "runs": "run",
}


def element_name(data, path) -> str | None:
    """A readable name of the element at ``path``: ``"joint 'A', point_i"``."""
    if not path:
        return None
    head, rest = path[0], list(path[1:])
    label = str(head)
    if head in _SECTIONS and rest and isinstance(rest[0], int):
        i = rest.pop(0)
        items = data.get(head) if isinstance(data, dict) else None
        name = None
        if isinstance(items, list) and i < len(items) and isinstance(items[i], dict):
            name = items[i].get("name")
        label = f"{_SECTIONS[head]} {name!r}" if isinstance(name, str) else f"{head}[{i}]"
    elif head == "parameters" and rest:
        label = f"parameter {rest.pop(0)!r}"
    if rest:
        text = ""
        for p in rest:
            text += f"[{p}]" if isinstance(p, int) else (f".{p}" if text else str(p))
        label += f", {text}"
    return label
