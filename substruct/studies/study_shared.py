"""The reduced substructures a study does not change: made once, shared by every sample.

A study varies some ``parameters``; every other value of the case is the same in each sample.
A reduced part (:func:`substruct.builder.parts.reduced_names`) is the same in each sample when
nothing it is made from names a varied parameter: its own entry of ``substructures``, the
points the case uses on it (finite-element nodes and a Craig-Bampton boundary are put there)
and, for a solid tied by ``interfaces:``, every interface and every tied solid with its points.
A parameter is varied when the study lists it, or when its expression names a varied parameter
(``kc: "1.1*k0"`` with ``k0`` varied).  The names are read from the case text (every identifier
of every string counts, so that a part is shared only when it cannot change).

Such a part is reduced once (:func:`substruct.builder.parts.reduced_part`: on the client, or as
one Dask task, then scattered to every worker) and every sample assembles its model with it
(``build_model(case, prebuilt=...)``): the same matrices as reducing it in each sample.
"""

from __future__ import annotations

import re
from typing import Any, Iterable

from substruct.builder.parts import reduced_names
from substruct.builder.points import point_uses
from substruct.case.fields import parse_point
from substruct.case.loader import Case
from substruct.case.yaml_io import load_yaml

__all__ = ["identifiers", "varied_parameters", "shared_parts"]

_NAME = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")


def identifiers(value: Any) -> set[str]:
    """Every identifier of every string in ``value`` (nested lists and mappings)."""
    if isinstance(value, str):
        return set(_NAME.findall(value))
    if isinstance(value, dict):
        return set().union(*(identifiers(v) for v in value.values())) if value else set()
    if isinstance(value, (list, tuple)):
        return set().union(*(identifiers(v) for v in value)) if value else set()
    return set()


def varied_parameters(raw: dict, study: Iterable[str]) -> set[str]:
    """The study's parameters and every parameter whose expression names one of them (in the
    order they are listed, as they are evaluated)."""
    varied = set(study)
    params = raw.get("parameters") or {}
    if isinstance(params, dict):
        for name, value in params.items():
            if identifiers(value) & varied:
                varied.add(str(name))
    return varied


def shared_parts(case: Case, study: Iterable[str]) -> list[str]:
    """The reduced substructures of ``case`` that no parameter of ``study`` can change."""
    raw = load_yaml(case.text, case.source)
    varied = varied_parameters(raw, study)
    entries = {str(s.get("name")): s for s in raw.get("substructures") or []
               if isinstance(s, dict)}
    points: dict[str, list[str]] = {}
    for use in point_uses(case):
        points.setdefault(parse_point(use.text)[0], []).append(use.text)
    tied = {n for item in case.interfaces for n in item.between}
    out = []
    for name in reduced_names(case):
        parts = sorted(tied) if name in tied else [name]
        made_of: list[Any] = [raw.get("interfaces") or []] if name in tied else []
        for part in parts:
            made_of += [entries.get(part, {}), points.get(part, [])]
        if not identifiers(made_of) & varied:
            out.append(name)
    return out
