"""Case-file errors as one line: ``<file>: <field.path>: <problem>, got <value>``.

:class:`CaseError` is what every layer reports bad input with (the command line prints it and
exits with code 2).  Validators raise :class:`FieldError` (a problem at a location relative to
the object being validated); :func:`translate` turns the first error of a pydantic
:class:`~pydantic.ValidationError` into a :class:`CaseError`, with the location written the way
a reader of the file finds it (:func:`field_path`), the value shown on one line
(:func:`show_value`) and, for a misspelt key, the closest allowed one ("did you mean").
"""

from __future__ import annotations

import difflib
import json
import re
import types
from typing import (
    Annotated,
    Any,
    Literal,
    Mapping,
    Sequence,
    Union,
    get_args,
    get_origin,
)

import numpy as np
from pydantic import BaseModel, ValidationError

from substruct.case.fields import NAME_PATTERN
from substruct.case.kinds import LINK_TYPES, SUBSTRUCTURE_KINDS
from substruct.case.lazy_models import lazy_model
from substruct.case.numbers import MAX_DIGITS, BigNumber
from substruct.case.text import printable

__all__ = ["CaseError", "FieldError", "MISSING", "show_value", "field_path", "translate",
           "printable"]

#: Marks "no value" (a missing field), as opposed to a value ``None`` (YAML ``null``).
MISSING: Any = object()
#: Longest value shown in a message (characters).
SHOWN = 80


def _json_default(obj: Any) -> Any:
    if isinstance(obj, BigNumber):
        return str(obj)
    if isinstance(obj, int):  # an int subclass json cannot write
        return _int_text(int(obj))
    if isinstance(obj, np.generic):
        return obj.item()
    return str(obj)


def _int_text(n: int) -> str:
    """``n`` in digits, shortened (never converted to text beyond 30 digits)."""
    if abs(n) <= 10 ** MAX_DIGITS:
        return str(n)
    digits = int(abs(n).bit_length() * 0.30103) + 1
    return f"{'-' if n < 0 else ''}an integer of about {digits} digits"


def _big_ints(value: Any, depth: int = 0) -> bool:
    """Whether ``value`` holds an ``int`` too long to write out (json would fail or stall)."""
    if isinstance(value, int) and not isinstance(value, bool):
        return abs(value) > 10 ** MAX_DIGITS
    if depth > 200 or not isinstance(value, (list, tuple, dict)):
        return False
    items = list(value.items()) if isinstance(value, dict) else list(enumerate(value))
    return any(_big_ints(k, depth + 1) or _big_ints(v, depth + 1) for k, v in items[:1000])


def _shorten(value: Any) -> Any:
    """``value`` with too-long integers replaced by their description (for json)."""
    if isinstance(value, int) and not isinstance(value, bool):
        return _int_text(value) if abs(value) > 10 ** MAX_DIGITS else value
    if isinstance(value, dict):
        return {(_int_text(k) if isinstance(k, int) and not isinstance(k, bool)
                 and abs(k) > 10 ** MAX_DIGITS else k): _shorten(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_shorten(v) for v in value]
    return value


def show_value(value: Any) -> str:
    """A value in an error message: one line, at most about :data:`SHOWN` characters."""
    if isinstance(value, np.generic):
        value = value.item()
    try:
        if isinstance(value, bool):
            text = "true" if value else "false"
        elif value is None:
            text = "null"
        elif isinstance(value, BigNumber):
            text = str(value)
        elif isinstance(value, int):
            text = _int_text(value)
        elif isinstance(value, str):
            text = repr(value if len(value) <= 4 * SHOWN else value[:4 * SHOWN])
        elif isinstance(value, float):
            text = repr(value)
        elif isinstance(value, (list, tuple, dict)):
            shown = _shorten(value) if _big_ints(value) else value
            try:
                text = json.dumps(shown, default=_json_default)
            except (TypeError, ValueError, RecursionError):
                text = repr(shown)
        elif isinstance(value, np.ndarray):
            text = f"array of shape {value.shape}"
        else:
            text = repr(value)
    except (ValueError, RecursionError):  # a value that cannot be written out
        text = f"a {type(value).__name__}"
    text = printable(text.replace("\n", "\\n"))
    return text if len(text) <= SHOWN else text[:SHOWN - 3] + "..."


def _rebuild(cls: type[Exception], message: str, state: dict[str, Any]) -> Exception:
    """An error of class ``cls`` with its message and attributes, without calling its
    ``__init__`` (whose arguments differ from class to class): the other half of
    :meth:`CaseError.__reduce__`."""
    err = cls.__new__(cls)
    Exception.__init__(err, message)
    err.__dict__.update(state)
    return err


class CaseError(ValueError):
    """A problem with a case file, as one line ``<file>: <field.path>: <problem>, got <value>``.

    Picklable (a run's child process and Dask workers send it back): it is rebuilt from its
    message and attributes, whatever the arguments of a subclass's ``__init__``.

    Attributes:
        source: the case file (or ``"<string>"``).
        path: the field path, e.g. ``substructures.rod.length`` (empty for the whole file).
        problem: what is wrong.
        value: the offending value (``None`` when there is none, e.g. a missing field).
    """

    def __init__(self, source: str, path: str, problem: str, value: Any = MISSING):
        self.source, self.path, self.problem = str(source), path, problem
        self.value = None if value is MISSING else value
        message = ": ".join([self.source] + ([path] if path else []) + [problem])
        if value is not MISSING:
            message += f", got {show_value(value)}"
        super().__init__(printable(message))

    def __reduce__(self) -> tuple[Any, ...]:
        return _rebuild, (type(self), str(self), dict(self.__dict__))


class FieldError(ValueError):
    """Raised inside validators: a problem at ``loc`` relative to the validated object
    (picklable like :class:`CaseError`)."""

    def __init__(self, loc: str | int | Sequence[str | int], problem: str,
                 value: Any = MISSING):
        self.loc = (loc,) if isinstance(loc, (str, int)) else tuple(loc)
        self.problem, self.value = problem, value
        super().__init__(problem)

    def __reduce__(self) -> tuple[Any, ...]:
        state = dict(self.__dict__)
        if state.get("value") is MISSING:  # the sentinel is this process's own object
            state["value"] = _Missing()
        return _rebuild, (type(self), str(self), state)


class _Missing:
    """Stands for :data:`MISSING` in a pickle; turned back into it on loading."""

    def __reduce__(self) -> tuple[Any, ...]:
        return _missing, ()


def _missing() -> Any:
    return MISSING


# ------------------------------------------------------------------------ field paths

#: Keys whose value selects a member of a tagged union in the case schema.
_DISCRIMINATORS = ("type", "method", "shape")


def _key(key: Any) -> str:
    """A mapping key in a field path: as written, or quoted (``'my key'``, ``'a\\x1b'``) when
    it holds spaces, quotes or characters that are not printable."""
    text = str(key)
    if text and text.isprintable() and not any(c.isspace() or c in "'\"" for c in text):
        return text
    return repr(text)


def field_path(loc: Sequence[str | int], raw: Any) -> str:
    """``substructures.rod.length`` / ``connections[2]`` from a location in the raw data.

    List items are named by their ``name`` when it is unique in the list, otherwise by their
    0-based index; union members and discriminator tags that pydantic puts into locations are
    left out.  Keys with spaces, quotes or unprintable characters are quoted.
    """
    out = ""
    node = raw
    for i, el in enumerate(loc):
        last = i == len(loc) - 1
        if isinstance(node, dict) and not last and isinstance(el, str) and \
                any(node.get(key) == el for key in _DISCRIMINATORS) and \
                (el not in node or loc[i + 1] in node):
            # a union tag pydantic put into the location (``type: mass``), unless it is also
            # the key the location goes on in (``method: modal`` beside ``modal: {..}``)
            continue
        if isinstance(node, dict) and isinstance(el, str) and el in node:
            out += ("." if out else "") + _key(el)
            node = node[el]
        elif isinstance(node, dict) and isinstance(el, int) and \
                any(isinstance(k, bool) and k == el for k in node):
            # a key true/false, which pydantic's location holds as 1/0
            key = next(k for k in node if isinstance(k, bool) and k == el)
            out += ("." if out else "") + ("true" if key else "false")
            node = node[key]
        elif isinstance(node, list) and isinstance(el, int) and 0 <= el < len(node):
            item = node[el]
            name = item.get("name") if isinstance(item, dict) else None
            names = [x.get("name") for x in node if isinstance(x, dict)]
            if isinstance(name, str) and names.count(name) == 1 and \
                    re.match(NAME_PATTERN, name):
                out += "." + name
            else:
                out += f"[{el}]"
            node = item
        elif isinstance(el, int):
            out += f"[{el}]"
            node = None
        elif last and el != "[key]" and (isinstance(node, dict) or node is None):
            out += ("." if out else "") + _key(el)
            node = None
    return out


# ------------------------------------------------------------- "unknown key" suggestions


def _unwrap(tp: Any, data: Any = None) -> Any:
    """``tp`` without ``Annotated``; a block imported when used is its model (the member that
    ``data`` names, for a union: :mod:`substruct.case.lazy_models`)."""
    while get_origin(tp) is Annotated:
        lazy = lazy_model(tp, data=data)
        tp = lazy if lazy is not None else get_args(tp)[0]
    return tp


def _members(tp: Any, data: Any = None) -> list[Any]:
    tp = _unwrap(tp, data)
    if get_origin(tp) in (Union, types.UnionType):
        return [_unwrap(a, data) for a in get_args(tp) if a is not type(None)]
    return [tp]


def _is_model(tp: Any) -> bool:
    return isinstance(tp, type) and issubclass(tp, BaseModel)


def _selected_by_tag(models: list[type[BaseModel]], tag: str) -> type[BaseModel] | None:
    """The member of a discriminated union whose ``Literal`` field admits ``tag``."""
    for m in models:
        for f in m.model_fields.values():
            tp = _unwrap(f.annotation)
            if get_origin(tp) is Literal and tag in get_args(tp):
                return m
    return None


def _allowed_keys(root: type[BaseModel], loc: Sequence[str | int],
                  raw: Any = None) -> list[str] | None:
    """Field names of the model at ``loc`` below ``root`` (for "unknown key" messages); ``raw``,
    the data validated, tells the member of a union imported when used."""
    tp: Any = root
    node = raw
    for el in loc:
        members = _members(tp, node)
        models = [m for m in members if _is_model(m)]
        nxt = None
        for m in models:
            if isinstance(el, str) and el in m.model_fields:
                field = m.model_fields[el]
                nxt = lazy_model(field.annotation, field.metadata) or field.annotation
                break
        if nxt is None and isinstance(el, str):
            nxt = _selected_by_tag(models, el)
        if nxt is None:
            for m in members:
                origin = get_origin(m)
                if origin is list and isinstance(el, int):
                    nxt = get_args(m)[0]
                elif origin is dict:
                    nxt = get_args(m)[1]
        if nxt is None:
            return None
        tp = nxt
        if isinstance(node, dict) and el in node:
            node = node[el]  # (a union tag in the location is no key: the node stays)
        elif isinstance(node, list) and isinstance(el, int) and 0 <= el < len(node):
            node = node[el]
    models = [m for m in _members(tp, node) if _is_model(m)]
    return list(models[0].model_fields) if len(models) == 1 else None


# ------------------------------------------------------------------ pydantic -> one line

_SIMPLE = {
    "finite_number": "must be a finite number",
    "float_parsing": "must be a number", "float_type": "must be a number",
    "int_parsing": "must be an integer", "int_type": "must be an integer",
    "int_parsing_size": "must be an integer of at most 30 digits",
    "int_from_float": "must be an integer",
    "bool_parsing": "must be true or false", "bool_type": "must be true or false",
    "string_type": "must be a string",
    "string_pattern_mismatch": "must be a name of letters, digits, '_', '.' and '-'",
    "string_too_short": "must not be empty",
    "list_type": "must be a list",
    "dict_type": "must be a mapping (key: value)",
    "model_type": "must be a mapping (key: value)",
    "model_attributes_type": "must be a mapping (key: value)",
    "tuple_type": "must be a list",
}
_TAGS = {"method": "assumed-modes, fe"}


def _expected_tags(disc: str, loc: tuple, ctx: Mapping[str, Any]) -> str:
    """The tags a discriminated field takes, for "expected one of": pydantic's own list when
    it gives one, else those of the list the item is in (substructures, links)."""
    expected = ctx.get("expected_tags")
    if expected:
        return ", ".join(t.strip().strip("'") for t in str(expected).split(","))
    if disc == "type" and loc and loc[0] == "substructures":
        return ", ".join(SUBSTRUCTURE_KINDS)
    if disc == "type" and loc and loc[0] == "links":
        return ", ".join(LINK_TYPES)
    return _TAGS.get(disc, "")


def _problem(err: Mapping[str, Any], loc: tuple, root: type[BaseModel], raw: Any = None
             ) -> tuple[str, tuple, Any]:
    """``(problem, loc, value)`` for one pydantic error."""
    typ, msg, ctx = err["type"], err["msg"], err.get("ctx") or {}
    value = err.get("input", MISSING)
    exc = ctx.get("error")
    if isinstance(exc, FieldError):
        return exc.problem, loc + exc.loc, exc.value
    if typ == "missing":
        return "required field is missing", loc, MISSING
    if typ == "extra_forbidden":
        allowed = [k for k in _allowed_keys(root, loc[:-1], raw) or [] if k != "values"]
        extra = f" (allowed: {', '.join(allowed)})" if allowed else ""
        close = difflib.get_close_matches(str(loc[-1]), allowed, n=1) if loc else []
        hint = f"; did you mean {close[0]!r}?" if close else ""
        return f"unknown key{hint}{extra}", loc, value
    if typ in ("union_tag_invalid", "union_tag_not_found"):
        disc = str(ctx.get("discriminator", "")).strip("'")
        tags = _expected_tags(disc, loc, ctx)
        if typ == "union_tag_not_found" and isinstance(value, dict):
            return (f"needs {disc}: one of {tags}" if tags else f"needs {disc}"), \
                loc + (disc,), MISSING
        if typ == "union_tag_not_found":
            return "must be a mapping (key: value)", loc, value
        expected = f" (expected one of {tags})" if tags else ""
        # the tag as written (null, 5, a list), not as pydantic's message text makes it
        tag = value[disc] if isinstance(value, dict) and disc in value else ctx.get("tag")
        return f"unknown {disc}{expected}", loc + (disc,), tag
    bounds = {
        "greater_than": f"must be > {ctx.get('gt')}",
        "greater_than_equal": f"must be >= {ctx.get('ge')}",
        "less_than_equal": f"must be <= {ctx.get('le')}",
        "too_short": f"must have at least {ctx.get('min_length')} item(s)",
        "too_long": f"must have at most {ctx.get('max_length')} item(s)",
        "string_too_long": f"must have at most {ctx.get('max_length')} characters",
        "literal_error": f"must be one of {ctx.get('expected')}",
    }
    if typ in _SIMPLE or typ in bounds:
        return _SIMPLE.get(typ) or bounds[typ], loc, value
    if typ == "value_error":
        return msg.removeprefix("Value error, "), loc, value
    return msg.replace("Input should be", "must be"), loc, value


def translate(exc: ValidationError, raw: Any, source: str, root: type[BaseModel],
              set_paths: Sequence[str] = ()) -> CaseError:
    """The first problem of a validation of ``raw`` against ``root``, as a :class:`CaseError`.

    Args:
        exc: the pydantic error.
        raw: the data validated (to name list items and find keys).
        source: the case file, for the message.
        root: the model validated (to list the allowed keys of an unknown one).
        set_paths: paths set by ``--set`` (a problem there says so).
    """
    errors = exc.errors(include_url=False)
    if not errors:
        return CaseError(source, "", " ".join(str(exc).split()))
    err = errors[0]  # in field order: the first problem a reader meets in the file
    if err["type"] == "missing":  # a misspelt key shows as missing + unknown: name the latter
        parent = tuple(err["loc"][:-1])
        err = next((e for e in errors if e["type"] == "extra_forbidden"
                    and tuple(e["loc"][:-1]) == parent), err)
    problem, loc, value = _problem(err, tuple(err["loc"]), root, raw)
    path = field_path(loc, raw)
    # an unknown key that --set made on the way to its value (analysis.mode of
    # analysis.mode.count) is of the command line too
    made = err["type"] == "extra_forbidden" and path and any(
        p.startswith(path + ".") or p.startswith(path + "[") for p in set_paths)
    if made or any(path == p or path.startswith(p + ".") or path.startswith(p + "[")
                   for p in set_paths):
        problem += " (set on the command line)"
    return CaseError(source, path, problem, value)
