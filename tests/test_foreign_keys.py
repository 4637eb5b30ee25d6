"""Every key of a case is used or refused, by construction.

Two walks:

* over the schema: every pydantic model reachable from :class:`~substruct.case.loader.Case`
  (through fields, lists, mappings and unions) forbids extra keys;
* over valid cases (the shipped ``cases/*.yaml`` and the whole cases of the docs): a foreign
  key injected into every mapping, one at a time, is refused with a one-line
  :class:`~substruct.case.errors.CaseError` naming the key.  Mappings whose keys are data (the
  points of ``constraints[].terms`` and ``rhs_force``, the names of ``parameters``) refuse it
  too: an unknown point when the model is built, a parameter that nothing uses when loaded.
"""

from __future__ import annotations

import copy
import re
import types
from pathlib import Path
from typing import Annotated, Any, Iterator, Union, get_args, get_origin

import pytest
import yaml
from pydantic import BaseModel

from substruct.case.errors import CaseError
from substruct.case.lazy_models import lazy_members
from substruct.case.loader import Case, parse_case
from substruct.run.runner import build_model

ROOT = Path(__file__).resolve().parents[1]
KEY = "zz_foreign"
#: Mappings whose keys are data, refused when the model is built (unknown point).
DATA_KEYED = ("terms", "rhs_force")


def _models(tp: Any, seen: set[type], metadata: Any = ()) -> Iterator[type[BaseModel]]:
    """Every pydantic model class reachable from the annotation ``tp`` (through the blocks
    imported when a case has them, too: :mod:`substruct.case.lazy_models`)."""
    for member in lazy_members(tp, metadata):
        yield from _models(member, seen)
    origin = get_origin(tp)
    if origin is Annotated:
        yield from _models(get_args(tp)[0], seen)
    elif origin in (Union, types.UnionType, list, dict, tuple) or (
            origin is not None and get_args(tp)):
        for arg in get_args(tp):
            yield from _models(arg, seen)
    elif isinstance(tp, type) and issubclass(tp, BaseModel) and tp not in seen:
        seen.add(tp)
        yield tp
        for field in tp.model_fields.values():
            yield from _models(field.annotation, seen, field.metadata)


def test_every_model_of_the_schema_forbids_extra_keys():
    models = list(_models(Case, set()))
    names = {m.__name__ for m in models}
    # the walk reaches every block (a walk that stopped early would prove nothing)
    assert {"Case", "Analysis", "ModesAnalysis", "FrfAnalysis", "Omega", "RodSpec",
            "SolidSpec", "MatrixSpec", "FrfSpec", "TransientAnalysis", "StudySpec",
            "ConstraintSpec", "Output"} <= names, names
    assert len(models) >= 30
    lenient = [m.__name__ for m in models if m.model_config.get("extra") != "forbid"]
    assert not lenient


def _doc_cases() -> list[tuple[str, str]]:
    """The ``yaml`` blocks of the docs that hold a whole case (``name`` and
    ``substructures``)."""
    out = []
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for k, text in enumerate(re.findall(r"^```yaml\s*\n(.*?)^```", page.read_text(),
                                            flags=re.S | re.M)):
            try:
                data = yaml.safe_load(text)
            except yaml.YAMLError:
                continue
            if isinstance(data, dict) and "name" in data and "substructures" in data:
                out.append((f"{page.name}#{k}", text))
    return out


CASES = [(p.name, p.read_text()) for p in sorted((ROOT / "cases").glob("*.yaml"))] + \
    _doc_cases()


def _mappings(node: Any, path: tuple = ()) -> Iterator[tuple]:
    if isinstance(node, dict):
        yield path
        for k, v in node.items():
            yield from _mappings(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _mappings(v, path + (i,))


def _at(node: Any, path: tuple) -> Any:
    for p in path:
        node = node[p]
    return node


@pytest.mark.parametrize("name, text", CASES, ids=[c[0] for c in CASES])
def test_a_foreign_key_is_refused_in_every_block(name, text, monkeypatch):
    monkeypatch.chdir(ROOT)  # files named in the docs' cases are relative to the project
    raw = yaml.safe_load(text)
    try:
        parse_case(yaml.safe_dump(raw), name, ROOT / "cases")
    except CaseError:
        pytest.skip("a docs case that needs files of its own page")
    paths = list(_mappings(raw))
    assert paths[0] == ()
    for path in paths:
        data = copy.deepcopy(raw)
        _at(data, path)[KEY] = 1
        with pytest.raises(CaseError) as info:
            case = parse_case(yaml.safe_dump(data), name, ROOT / "cases")
            assert path and path[-1] in DATA_KEYED, f"accepted at {path}"
            build_model(case)
        message = str(info.value)
        assert KEY in message, (path, message)
        assert "\n" not in message


def test_an_unused_parameter_is_refused_and_a_used_one_is_not():
    text = (ROOT / "cases" / "three_dof_frf.yaml").read_text()
    parse_case(text, "three_dof_frf.yaml")
    with pytest.raises(CaseError, match=r"^three_dof_frf.yaml: parameters.kk1: a parameter "
                                        r"that nothing uses .* \(set on the command line\), "
                                        r"got 5$"):
        parse_case(text, "three_dof_frf.yaml", overrides=["parameters.kk1=5"])
    # a parameter used only by another parameter is used
    chained = text.replace("c: 10.0}", "c: 2 * c0}").replace("parameters: {",
                                                            "parameters: {c0: 5.0, ")
    assert parse_case(chained, "three_dof_frf.yaml").parameters["c"] == 10.0
