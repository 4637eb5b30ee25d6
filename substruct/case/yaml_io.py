"""Case-file YAML: a strict safe loader and the ``--set key.path=value`` overrides.

The loader is PyYAML's safe loader with two changes: a duplicate key in a mapping is an error
(PyYAML silently keeps the last one), and numbers with an exponent (``6e6``, ``2e-3``) are
numbers, as in YAML 1.2.  A syntax error is reported with its line and column.

Overrides address a value by its path in the raw data: mapping keys joined by dots, list items
by 0-based index (``connections.0``, ``connections[0]``) or by their ``name``
(``substructures.c.stiffness``).
"""

from __future__ import annotations

import re
from typing import Any, Sequence

import yaml

from substruct.case.errors import CaseError
from substruct.case.numbers import MAX_DIGITS, BigNumber

__all__ = ["load_yaml", "apply_overrides", "MAX_NESTING", "MAX_ALIAS_EXPANSION",
           "MAX_SET_LENGTH"]


#: Deepest nesting of lists and mappings accepted (a case file needs about 6 levels).
MAX_NESTING = 20


class _Loader(yaml.SafeLoader):
    """Safe loader that refuses duplicate keys and deep nesting and reads ``6e6`` as a number.

    Nesting is limited while scanning: PyYAML's scanner is quadratic in the depth of flow
    collections (``[[[[...``) and its composer recursive.
    """

    def _too_deep(self) -> None:
        raise yaml.scanner.ScannerError(None, None, f"nested more than {MAX_NESTING} levels "
                                        f"deep", self.get_mark())

    def fetch_flow_collection_start(self, TokenClass):  # noqa: N803 - PyYAML's name
        if self.flow_level >= MAX_NESTING:
            self._too_deep()
        super().fetch_flow_collection_start(TokenClass)

    def add_indent(self, column: int) -> bool:
        if len(self.indents) >= MAX_NESTING:
            self._too_deep()
        return super().add_indent(column)


def _mapping(loader: _Loader, node: yaml.MappingNode, deep: bool = False) -> dict:
    """A mapping whose keys are written once; keys merged in (``<<: *anchor``) may be
    overridden by the mapping's own keys, which come after them."""
    written = {id(k) for k, _ in node.value if k.tag != "tag:yaml.org,2002:merge"}
    loader.flatten_mapping(node)
    out: dict = {}
    seen: set = set()
    for key_node, value_node in node.value:
        key = loader.construct_object(key_node, deep=deep)
        try:
            hash(key)
        except TypeError:
            raise yaml.constructor.ConstructorError(
                None, None, "unhashable key", key_node.start_mark) from None
        if id(key_node) in written:
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark)
            seen.add(key)
        out[key] = loader.construct_object(value_node, deep=deep)
    return out


def _int(loader: _Loader, node: yaml.ScalarNode) -> Any:
    """An integer, or a :class:`~substruct.case.numbers.BigNumber` when it is written with
    more than :data:`~substruct.case.numbers.MAX_DIGITS` digits (never converted: Python
    refuses to convert more than 4300 digits, and ``float()`` of a huge one overflows)."""
    text = str(loader.construct_scalar(node))
    big = BigNumber(text)
    if big.digits > MAX_DIGITS:
        return big
    return yaml.constructor.SafeConstructor.construct_yaml_int(loader, node)


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _mapping)
_Loader.add_constructor("tag:yaml.org,2002:int", _int)
# YAML 1.1 (PyYAML) reads 6e6, 6.0e6 and 2e-3 as strings; read them as numbers, as YAML 1.2 does
_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"))


#: Values that aliases (``*name``) may add to a file beyond what it spells out.
MAX_ALIAS_EXPANSION = 1_000_000


def _expansion(data: Any) -> tuple[int, int]:
    """``(expanded, stored)``: values in ``data`` with every alias expanded, and as stored.

    Raises:
        ValueError: a structure that contains itself (``&a [*a]``).
    """
    sizes: dict[int, int] = {}
    active: set[int] = set()
    stored = 0

    def size(node: Any) -> int:
        nonlocal stored
        if not isinstance(node, (list, dict)):
            return 1
        key = id(node)
        if key in sizes:
            return sizes[key]
        if key in active:
            raise ValueError("a structure that contains itself (through an alias)")
        active.add(key)
        children = list(node.values()) if isinstance(node, dict) else node
        stored += 1 + len(children)
        n = 1 + sum(size(child) for child in children)
        active.discard(key)
        sizes[key] = n
        return n

    return size(data), stored


def _check_aliases(data: Any, source: str, where: str = "", value: Any = None) -> None:
    """Refuse ``data`` whose aliases expand beyond :data:`MAX_ALIAS_EXPANSION` values or make
    it contain itself (``where`` and ``value`` name a ``--set`` override)."""
    shown = () if value is None else (value,)
    try:
        expanded, stored = _expansion(data)
    except ValueError as err:
        raise CaseError(source, where, f"invalid YAML: {err}", *shown) from None
    except RecursionError:
        raise CaseError(source, where, "invalid YAML: nested too deeply", *shown) from None
    if expanded > stored + MAX_ALIAS_EXPANSION:
        raise CaseError(source, where, f"invalid YAML: aliases expand to more than "
                        f"{MAX_ALIAS_EXPANSION} values ({expanded} values from {stored} "
                        f"written)", *shown)


def load_yaml(text: str, source: str) -> Any:
    """Parse case-file text.

    Anchors and aliases are allowed, but not aliases that multiply the file beyond
    :data:`MAX_ALIAS_EXPANSION` values (a "billion laughs") or make it contain itself.
    Integers of more than :data:`~substruct.case.numbers.MAX_DIGITS` digits are read as
    :class:`~substruct.case.numbers.BigNumber` (refused by the validation, by name).

    Raises:
        CaseError: ``<source>: line L, column C: invalid YAML: <problem>``.
    """
    data = _parse(text, source)
    _check_aliases(data, source)
    return data


def _parse(text: str, source: str) -> Any:
    try:
        return yaml.load(text, Loader=_Loader)  # noqa: S506 - a SafeLoader subclass
    except yaml.MarkedYAMLError as err:
        mark = err.problem_mark or err.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        what = err.problem or err.context or "syntax error"
        raise CaseError(source, where, f"invalid YAML: {what}") from None
    except yaml.YAMLError as err:
        raise CaseError(source, "", f"invalid YAML: {' '.join(str(err).split())}") from None
    except RecursionError:
        raise CaseError(source, "", "invalid YAML: nested too deeply") from None
    except (ValueError, OverflowError, MemoryError) as err:  # a scalar PyYAML cannot convert
        raise CaseError(source, "", f"invalid YAML: {type(err).__name__}: "
                        f"{' '.join(str(err).split())[:120]}") from None


# ---------------------------------------------------------------------------- --set

#: Longest ``--set`` override (key and value) accepted, in characters.
MAX_SET_LENGTH = 20_000


def _split_key(key: str) -> list[str | int]:
    """``a.b[2].c`` -> ``["a", "b", 2, "c"]``; bracketed parts are indices or names."""
    parts: list[str | int] = []
    for piece in key.split("."):
        m = re.fullmatch(r"([^\[\]]*)((?:\[[^\[\]]*\])*)", piece)
        if m is None:
            raise ValueError(f"cannot parse key {key!r}")
        if m.group(1):
            parts.append(m.group(1))
        for idx in re.findall(r"\[([^\[\]]*)\]", m.group(2)):
            parts.append(int(idx) if re.fullmatch(r"-?\d+", idx) else idx)
    if not parts or any(p == "" for p in parts):
        raise ValueError(f"cannot parse key {key!r}")
    if len(parts) > MAX_NESTING:
        raise ValueError(f"a key path of {len(parts)} parts, more than the {MAX_NESTING} "
                         f"levels a case may nest")
    return parts


def _where(key: str) -> str:
    """``--set <key>`` for a message, the key shortened to 60 characters."""
    key = key.strip()
    return f"--set {key if len(key) <= 60 else key[:57] + '...'}"


def _set_one(data: dict, key: str, value: Any, source: str) -> str:
    """Apply one override; return its canonical path (as error messages write it)."""
    where = _where(key)
    try:
        parts = _split_key(key)
    except ValueError as err:
        raise CaseError(source, where, str(err)) from None
    node: Any = data
    path = ""
    i = 0
    while True:
        if isinstance(node, dict):
            # the longest run of parts that is a key (names may contain dots)
            for j in range(len(parts), i, -1):
                cand = ".".join(str(p) for p in parts[i:j])
                if cand in node:
                    break
            else:
                j = i + 1
                cand = str(parts[i])
            path += ("." if path else "") + cand
            if j == len(parts):
                node[cand] = value
                return path
            if cand not in node or node[cand] is None:
                node[cand] = {}
            node, i = node[cand], j
        elif isinstance(node, list):
            p = parts[i]
            if isinstance(p, int) or (isinstance(p, str) and re.fullmatch(r"-?\d+", p)):
                k = int(p)
                j = i + 1
                if k == len(node) and j == len(parts):  # one past the end: append
                    node.append(value)
                    return f"{path}[{k}]"
                if not -len(node) <= k < len(node):
                    raise CaseError(source, where, f"no item {k} in {path} "
                                    f"({len(node)} items; {len(node)} appends one)")
                k %= len(node)
                item = node[k]
                name = item.get("name") if isinstance(item, dict) else None
                path += f".{name}" if isinstance(name, str) else f"[{k}]"
            else:
                names = [x.get("name") if isinstance(x, dict) else None for x in node]
                for j in range(len(parts), i, -1):
                    cand = ".".join(str(q) for q in parts[i:j])
                    if cand in names:
                        break
                else:
                    known = ", ".join(str(n) for n in names if n is not None) or "none"
                    raise CaseError(source, where, f"no item named {parts[i]!r} in {path} "
                                    f"(names: {known})")
                k = names.index(cand)
                path += "." + cand
            if j == len(parts):
                node[k] = value
                return path
            node, i = node[k], j
        else:
            raise CaseError(source, where, f"{path} is a value, not a mapping or list",
                            node)


def apply_overrides(data: dict, overrides: Sequence[str], source: str = "<string>"
                    ) -> list[str]:
    """Apply ``key.path=value`` overrides to the raw case ``data`` in place.

    List items are addressed by 0-based index (``connections.0`` or ``connections[0]``) or by
    their ``name`` (``substructures.c.stiffness``); the index one past the end appends an item
    (``constraints[1]={...}``); values are parsed as YAML
    (``--set analysis.frf.omega=[1,2,3]`` gives a list).  Missing mapping keys are created
    (validation then rejects unknown ones).

    Returns:
        The canonical paths set, as validation errors write them.

    Values are read by the case-file loader with its limits (nesting, aliases, no Python
    tags, integers of more than 30 digits kept as text); an override is at most
    :data:`MAX_SET_LENGTH` characters.

    Raises:
        CaseError: an override that is not ``key=value``, whose value is not YAML or whose
            path does not lead anywhere.
    """
    paths = []
    for item in overrides:
        item = str(item)
        key, eq, text = item.partition("=")
        if len(item) > MAX_SET_LENGTH:
            raise CaseError(source, _where(key), f"an override of "
                            f"{len(item)} characters, more than the {MAX_SET_LENGTH} accepted "
                            f"(put large values in the case file)", text)
        if not eq or not key.strip():
            raise CaseError(source, _where(item), "expected key.path=value")
        where = _where(key)
        try:
            value = yaml.load(text, Loader=_Loader) if text.strip() else None  # noqa: S506
        except yaml.YAMLError as err:
            what = getattr(err, "problem", None) or " ".join(str(err).split())[:80]
            raise CaseError(source, where, f"value is not valid YAML ({what})", text) from None
        except RecursionError:
            raise CaseError(source, where, "value is not valid YAML (nested too deeply)",
                            text) from None
        except (ValueError, OverflowError, MemoryError) as err:
            raise CaseError(source, where, f"value is not valid YAML ({type(err).__name__}: "
                            f"{' '.join(str(err).split())[:80]})", text) from None
        _check_aliases(value, source, where, text)
        paths.append(_set_one(data, key.strip(), value, source))
    return paths
