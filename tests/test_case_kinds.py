"""The case schema's blocks loaded only when a case has them (substruct.case.lazy_models,
substruct.case.kinds): the same models validate them, the kinds are told apart by their tag
exactly as by their class, and a case without a block does not import its module."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Literal, get_args, get_origin

import pytest

from substruct.case import kinds
from substruct.case.lazy_models import lazy_members
from substruct.case.loader import Case, load_case

ROOT = Path(__file__).resolve().parents[1]

#: Modules of blocks a rod case with modes does not have.
LAZY_MODULES = ["substruct.case.transient", "substruct.case.spec_analysis",
                "substruct.case.testlab_analysis", "substruct.case.solids",
                "substruct.case.frames", "substruct.case.superelements",
                "substruct.case.frf_substructure", "substruct.case.matrices",
                "substruct.case.links", "substruct.case.study"]


def _tags(model: type) -> tuple[str, ...]:
    annotation = model.model_fields["type"].annotation
    assert get_origin(annotation) is Literal
    return get_args(annotation)


def test_the_kinds_table_names_every_model_by_its_own_tags():
    field = Case.model_fields["substructures"]
    (item,) = get_args(field.annotation)
    models = lazy_members(item)
    assert len(models) == 10  # rod, discrete, spring, mass, matrices, solid, frf, frame, ...
    table = {tag: model for model in models for tag in _tags(model)}
    assert sorted(table) == sorted(kinds.SUBSTRUCTURE_KINDS)
    for tag, (module, name) in kinds.SUBSTRUCTURE_KINDS.items():
        assert (table[tag].__module__, table[tag].__name__) == (module, name)


def test_the_link_types_are_the_links_models_tags():
    from substruct.case.links import LinkSpec
    union, _ = get_args(LinkSpec)
    assert sorted(t for model in get_args(union) for t in _tags(model)) == \
        sorted(kinds.LINK_TYPES)


@pytest.mark.parametrize("check, name", [
    (kinds.is_solid, "SolidSpec"), (kinds.is_frame, "FrameSpec"),
    (kinds.is_superelement, "SuperelementSpec"), (kinds.is_nastran, "NastranSpec"),
    (kinds.is_matrices, "MatrixSpec"), (kinds.is_frf, "FrfSpec")])
def test_a_kind_is_told_by_its_tag_as_by_its_class(check, name):
    for tag, (_, model) in kinds.SUBSTRUCTURE_KINDS.items():
        assert check(SimpleNamespace(type=tag)) == (model == name), tag
    assert not check(None)


def test_validated_through_the_lazy_fields_the_models_are_the_same_classes():
    from substruct.case.frames import FrameSpec
    from substruct.case.links import InterpolationLinkSpec, RigidLinkSpec
    from substruct.case.nastran import NastranSpec
    from substruct.case.solids import SolidSpec

    case = load_case(ROOT / "cases" / "frame_solid_links.yaml")
    assert [type(s) for s in case.substructures] == [SolidSpec, FrameSpec, NastranSpec]
    assert [type(link) for link in case.links] == [InterpolationLinkSpec, RigidLinkSpec]
    assert case.model_dump()["links"][1]["dependents"] == ["arm@100"]


def _imported_after_loading(case: str) -> dict[str, bool]:
    code = ("import json, sys; from substruct.case.loader import load_case; "
            f"load_case({case!r}); "
            f"print(json.dumps({{m: m in sys.modules for m in {LAZY_MODULES!r}}}))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_a_rod_case_imports_no_block_it_does_not_have():
    loaded = _imported_after_loading("cases/tapered_rod_fe.yaml")
    assert not any(loaded.values()), loaded


def test_a_case_with_a_block_imports_its_module():
    loaded = _imported_after_loading("cases/frame_solid_links.yaml")
    for module in ("solids", "frames", "links"):
        assert loaded[f"substruct.case.{module}"], module
    assert not loaded["substruct.case.transient"]
