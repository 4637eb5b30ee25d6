"""A study's parameters must reach the model and not be set twice
(substruct/studies/study_inputs.py): a varied parameter that nothing uses, or one that
``--set`` also gives, would give a table whose rows are not what they say."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cli_helpers import assert_one_line_error, run
from substruct.io.study_file import load_study

CASE = """name: tuned
description: absorber c of stiffness kc on a grounded mass
parameters: {k0: 1000.0, kc: "1.1*k0", zz: 1.0}
substructures:
  - {name: a, type: fixed-free, mass: 2, stiffness: 5000}
  - {name: c, type: free-free, mass: 0.1, stiffness: kc}
connections:
  - [a, c]
analysis:
  modes: {count: 2}
study:
  grid:
    parameters:
      - {parameter: VARIED, values: [900, 1100]}
  collect: {frequencies: 2}
output: {pictures: false}
"""


def _case(tmp_path: Path, varied: str) -> Path:
    path = tmp_path / "tuned.yaml"
    text = CASE.replace("VARIED", varied)
    path.write_text(text if varied == "zz" else text.replace(", zz: 1.0", ""))
    return path


def test_a_parameter_computed_from_the_varied_one_carries_it(tmp_path, capsys):
    """k0 reaches the model through kc = 1.1 k0: the study runs, the absorber's frequency
    follows sqrt(1.1 k0 / m) as the closed form of the two-mass chain says."""
    code, _, err = run(capsys, "study", _case(tmp_path, "k0"), "--out", tmp_path / "out")
    assert code == 0, err
    study = load_study(tmp_path / "out" / "tuned_study.h5")
    for row, k0 in zip(study.values["frequency"], (900.0, 1100.0)):
        kc, m1, m2, k1 = 1.1 * k0, 2.0, 0.1, 5000.0
        K = np.array([[k1 + kc, -kc], [-kc, kc]])
        w = np.sqrt(np.linalg.eigvals(np.linalg.solve(np.diag([m1, m2]), K)).real)
        np.testing.assert_allclose(np.sort(row), np.sort(w), rtol=1e-10)


def test_a_varied_parameter_that_nothing_uses_is_refused(tmp_path, capsys):
    """zz is named only by the study (and kc's name only in the description): every sample
    would have been the same model, a table of identical rows, exit 0."""
    code, out, err = run(capsys, "study", _case(tmp_path, "zz"), "--out", tmp_path / "out")
    assert_one_line_error(code, out, err, "parameters.zz: the study varies this parameter but "
                          "no field of the case uses it", "got 1.0")
    assert not (tmp_path / "out").exists()


def test_a_varied_parameter_whose_use_set_replaced_is_refused(tmp_path, capsys):
    code, out, err = run(capsys, "study", _case(tmp_path, "kc"), "--out", tmp_path / "out",
                         "--set", "substructures.c.stiffness=1200")
    assert_one_line_error(code, out, err, "parameters.kc: the study varies this parameter but "
                          "no field of the case uses it")


def test_set_of_a_varied_parameter_is_refused(tmp_path, capsys):
    """Each sample's value is applied after the command line's: the --set would have been
    replaced in every sample without a word."""
    code, out, err = run(capsys, "study", _case(tmp_path, "kc"), "--out", tmp_path / "out",
                         "--set", "parameters.kc=5000")
    assert_one_line_error(code, out, err, "parameters.kc: the study varies this parameter: its "
                          "values replace the one of --set", "got '5000'")
    # a --set of another parameter is the study's base, as documented
    code, _, err = run(capsys, "study", _case(tmp_path, "kc"), "--out", tmp_path / "out",
                       "--set", "parameters.k0=2000")
    assert code == 0, err
