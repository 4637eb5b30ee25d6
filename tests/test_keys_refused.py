"""Case keys that used to be accepted and ignored, or read loosely, and are now used or refused
in one line (exit 2): the modal block of a direct receptance sweep, the range keys of a study
axis given by values, booleans that are strings or numbers, an unknown key made by --set; the
tuning map of a zip study; the docs' snippets that did not run; the messages for empty files,
numbers with units and notes in parentheses."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from substruct.case.loader import CaseError, load_case, parse_case

THREE_DOF = """
name: three_dof
substructures:
  - name: P
    type: matrices
    M: [[1, 0, 0], [0, 2, 0], [0, 0, 4]]
    K: [[20, -10, 0], [-10, 30, -20], [0, -20, 20]]
"""


def message(text: str, overrides: tuple[str, ...] = ()) -> str:
    """The one-line message of the CaseError that a case raises."""
    with pytest.raises(CaseError) as info:
        parse_case(text, "c.yaml", ".", overrides)
    return str(info.value)


def frf(method: str, modal: str) -> str:
    return THREE_DOF + (f"analysis:\n  frf: {{omega: [2.0], inputs: [P@q1], outputs: [P@q1], "
                        f"method: {method}, modal: {modal}}}\n")


@pytest.mark.parametrize("method", ["generalized-inverse", "null-space", "kkt"])
@pytest.mark.parametrize("modal", ["{cutoff: 10}", "{solver: amls, cutoff: 3}", "{}"])
def test_frf_modal_block_with_a_direct_method_is_refused(method, modal):
    assert message(frf(method, modal)) == (
        f"c.yaml: analysis.frf.modal: the modal block is for method: modal (or auto, which "
        f"sums the modes on a large model); the method is {method}, got '{{...}}'")


@pytest.mark.parametrize("method", ["modal", "auto"])
def test_frf_modal_block_is_taken_by_modal_and_auto(method):
    case = parse_case(frf(method, "{cutoff: 4, solver: amls}"), "c.yaml")
    assert case.analysis.frf.modal.cutoff == 4 and case.analysis.frf.modal.solver == "amls"


def test_frf_without_a_modal_block_keeps_any_method():
    for method in ("generalized-inverse", "kkt", "modal", "auto"):
        text = THREE_DOF + (f"analysis:\n  frf: {{omega: [2.0], inputs: [P@q1], "
                            f"outputs: [P@q1], method: {method}}}\n")
        assert parse_case(text, "c.yaml").analysis.frf.method == method


def test_frf_modal_block_refused_when_set_makes_the_method_direct():
    text = frf("modal", "{cutoff: 10}")
    assert "the method is kkt" in message(text, ("analysis.frf.method=kkt",))


SPRING_STUDY = """
name: spring_mass_study
parameters: {k: 100, m: 1, c: 0.1}
substructures:
  - {name: s, type: fixed-free, mass: m, stiffness: k, damping: c}
analysis:
  modes: {count: 1}
study:
  grid:
    parameters:
      - {parameter: k, %s}
  collect: {frequencies: 1}
"""


@pytest.mark.parametrize("extra,key,value", [
    ("spacing: log", "spacing", "'log'"), ("spacing: linear", "spacing", "'linear'"),
    ("start: 5", "start", "5.0"), ("stop: 6", "stop", "6.0"), ("num: 3", "num", "3")])
def test_a_values_axis_refuses_the_keys_of_a_range(extra, key, value):
    text = SPRING_STUDY % f"values: [100, 150], {extra}"
    assert message(text) == (
        f"c.yaml: study.grid.parameters[0].{key}: not a key of an axis given by values (start, "
        f"stop, num and spacing make a range, without values), got {value}")


def test_a_range_axis_takes_its_spacing():
    case = parse_case(SPRING_STUDY % "start: 1, stop: 100, num: 3, spacing: log", "c.yaml")
    assert case.study.grid.parameters[0].spacing == "log"
    case = parse_case(SPRING_STUDY % "values: [100, 150]", "c.yaml")
    assert case.study.grid.parameters[0].values == [100, 150]


SPRING = """
name: spring_mass
substructures:
  - {name: s, type: fixed-free, mass: 1, stiffness: 100}
  - {name: t, type: free-free, mass: 1, stiffness: 100}
connections:
  - [s, t]
constraints:
  - {name: c, terms: {s: 1, t@mass: -1}}
analysis:
  modes: {count: 1}
"""
BOOLEANS = [("output.pictures", "pictures"), ("output.matrices", "matrices"),
            ("constraints.c.active", "active")]


@pytest.mark.parametrize("path,key", BOOLEANS)
@pytest.mark.parametrize("text,shown", [('"yes"', "'yes'"), ('"no"', "'no'"), ('"off"', "'off'"),
                                        ("0", "0"), ("1", "1"), ("null", "null"),
                                        ('"true"', "'true'")])
def test_a_boolean_is_a_yaml_boolean_only(path, key, text, shown):
    assert message(SPRING, (f"{path}={text}",)) == (
        f"c.yaml: {path}: must be true or false (set on the command line), got {shown}")


def test_booleans_in_the_file_and_yaml_yes_no():
    case = parse_case(SPRING + "output: {pictures: no, matrices: true}\n", "c.yaml")
    assert case.output.pictures is False and case.output.matrices is True
    assert message(SPRING + "output: {pictures: 'off'}\n") == (
        "c.yaml: output.pictures: must be true or false, got 'off'")
    study = SPRING.replace("mass: 1, stiffness: 100}", "mass: 1, stiffness: k}", 1)
    study = "parameters: {k: 100}\n" + study + (
        "study:\n  grid: {parameters: [{parameter: k, values: [1, 2]}]}\n"
        "  collect: {frequencies: 1, track: 1}\n")
    assert message(study) == "c.yaml: study.collect.track: must be true or false, got 1"


def test_an_unknown_key_made_by_set_says_so():
    assert message(SPRING, ("analysis.mode.count=4",)) == (
        "c.yaml: analysis.mode: unknown key; did you mean 'modes'? (allowed: modes, frf, "
        "transient, random, base_frf, srs, tpa, semm) (set on the command line), got "
        '{"count": 4}')
    assert message(SPRING, ("outputs.pictures=false",)).startswith(
        "c.yaml: outputs: unknown key; did you mean 'output'? (allowed: ")
    assert message(SPRING, ("outputs.pictures=false",)).endswith(
        '(set on the command line), got {"pictures": false}')
    assert message(SPRING, ("substructures.s.dampin=1",)).endswith(
        "(set on the command line), got 1")


def test_an_unknown_key_of_the_file_does_not_blame_the_command_line():
    text = SPRING + "outputs: {pictures: false}\n"
    assert "(set on the command line)" not in message(text, ("analysis.modes.count=2",))
    assert "(set on the command line)" not in message(text)


def study_result(table, peaks):
    from substruct.studies.study_run import StudyResult

    table = np.asarray(table, float)
    return StudyResult(case_name="s", kind="grid", parameters=["kc", "cc"], table=table,
                       values={"frequency": np.outer(table[:, 0], [1.0, 2.0]),
                               "frf_peak": np.asarray(peaks, float)[:, None]},
                       errors=[""] * len(table), seconds=np.zeros(len(table)),
                       peaks=["rod@200<-rod@200"])


def test_the_tuning_map_is_drawn_for_a_product_grid_only(tmp_path):
    from substruct.viz.study_picture import is_product, study_pictures

    product = [[1, 3], [1, 4], [2, 3], [2, 4]]
    zipped = [[1, 3], [2, 3.5], [3, 4]]
    assert is_product(np.array(product)) and not is_product(np.array(zipped))
    assert not is_product(np.array([[1, 3], [1, 4], [2, 3]]))  # a product with a hole
    assert not is_product(np.array([[1, 3], [1, 3], [2, 4], [2, 4]]))  # repeated samples
    names = [p.name for p in study_pictures(study_result(product, [4, 3, 2, 1]), tmp_path)]
    assert names == ["s_study_frequencies.png", "s_study_tuning.png"]
    for p in tmp_path.iterdir():
        p.unlink()
    names = [p.name for p in study_pictures(study_result(zipped, [3, 2, 1]), tmp_path)]
    assert names == ["s_study_frequencies.png"]


# ------------------------------------------------------------------------ docs that run

ROOT = Path(__file__).resolve().parent.parent


def test_the_by_point_initial_state_of_transient_md_runs_on_its_rod():
    from substruct.run.runner import run_case

    line = next(ln for ln in (ROOT / "docs" / "transient.md").read_text().splitlines()
                if ln.strip().startswith("initial: {displacement:"))
    value = line.split("initial:", 1)[1].split("#")[0].strip()
    case = load_case(ROOT / "cases" / "tapered_rod_impact.yaml",
                     [f"analysis.transient.initial={value}", "analysis.transient.t_end=0.001",
                      "analysis.transient.check=[]", "output.pictures=false"])
    result = run_case(case).transient
    assert result is not None


def test_the_quoted_flow_terms_of_case_files_md_read_as_two_points():
    text = (ROOT / "docs" / "case-files.md").read_text()
    flow = re.search(r'`terms: (\{"right@[^`]*\})`', text).group(1)
    case = load_case(ROOT / "cases" / "box_beam_tmd.yaml", [f"constraints[0].terms={flow}"])
    assert case.constraints[0].terms == {"right@1,0,0.1:z": 1.0, "right@1,0.1,0.1:z": -1.0}


@pytest.mark.parametrize("page", ["README.md", "docs/case-files.md"])
def test_the_tables_of_cases_name_every_case(page):
    text = (ROOT / page).read_text()
    shipped = sorted(p.name for p in (ROOT / "cases").iterdir()
                     if p.suffix in (".yaml", ".bdf"))
    assert [name for name in shipped if f"`{name}`" not in text] == []


def test_readme_says_which_cases_make_run_runs():
    ran = re.findall(r"substruct run cases/(\S+)", (ROOT / "Makefile").read_text())
    said = (ROOT / "README.md").read_text().split("`make run` leaves", 1)[1].split("\n\n")[0]
    assert ran and all(f"`{name}`" in said for name in ran)


# ------------------------------------------------------------------------ messages

@pytest.mark.parametrize("text,number", [("200 mm", "200"), ("200mm", "200"),
                                         ("6e6 N/mm^2", "6e6"), ("-3 kg", "-3")])
def test_a_number_with_a_unit_says_units_are_not_accepted(text, number):
    from substruct.case.expressions import ExpressionError, compile_expression

    with pytest.raises(ExpressionError) as info:
        compile_expression(text)
    assert str(info.value) == (
        f"units are not accepted in numbers: write '{number}' alone (the numbers are in the "
        f"case's consistent units, its units: note converts nothing)")


@pytest.mark.parametrize("text", ["2 pi", "2 x", "x x"])
def test_a_known_name_after_a_number_is_a_plain_syntax_error(text):
    from substruct.case.expressions import ExpressionError, compile_expression

    with pytest.raises(ExpressionError, match=r"^syntax error in "):
        compile_expression(text)


def test_a_note_in_parentheses_says_where_a_comment_goes():
    text = SPRING.replace("mass: 1, stiffness: 100}", 'mass: 1, stiffness: "100 (steel)"}', 1)
    assert message(text) == (
        "c.yaml: substructures.s.stiffness: '100' followed by parentheses in '100 (steel)': a "
        "comment goes after # outside the quotes (100 # ...), a product needs * (2*(x + 1)), "
        "got '100 (steel)'")


def test_an_empty_load_table_says_so_without_a_numpy_warning(tmp_path, recwarn):
    from substruct.case.transient_files import read_table

    for text in ("", "\n\n", "# t, value\n"):
        (tmp_path / "t.csv").write_text(text)
        with pytest.raises(ValueError) as info:
            read_table(tmp_path / "t.csv")
        assert str(info.value) == ("the file is empty (or only comments): a CSV table has rows "
                                   "t, value")
    assert not recwarn.list
