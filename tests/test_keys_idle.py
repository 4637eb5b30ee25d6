"""Keys and values that were accepted and then not used, now refused in one line (exit 2): a
check naming the analysis's own method or named twice (dropped: the check never ran),
``modal_count`` of a transient without the modal form, a ``field_every`` that the recorded
steps do not hold (the fields were kept every ``lcm(every, field_every)`` steps), and
``export --format uff --transient`` (the option was ignored)."""

from __future__ import annotations

import numpy as np
import pytest

from substruct import cli
from substruct.case.loader import CaseError, parse_case

THREE_DOF = """
name: three_dof
substructures:
  - name: P
    type: matrices
    M: [[1, 0, 0], [0, 2, 0], [0, 0, 4]]
    K: [[20, -10, 0], [-10, 30, -20], [0, -20, 20]]
    C: [[1, 0, 0], [0, 0, 0], [0, 0, 0]]
constraints:
  - {name: c1, terms: {P@q1: 1, P@q2: -1, P@q3: 2}}
output: {pictures: false}
"""

ANALYSES = {
    "modes": "modes: {count: 2, method: METHOD, check: CHECK}",
    "frf": "frf: {omega: [2.0], inputs: [P@q1], outputs: [P@q1], method: METHOD, check: CHECK}",
    "base_frf": "base_frf: {omega: [2.0], base: {at: [P@q3]}, outputs: [P@q1], method: METHOD, "
                "check: CHECK}",
    "random": "random: {frequencies: [1, 2], forces: [{at: P@q1, psd: [[1, 1], [2, 1]]}], "
              "outputs: [P@q1], method: METHOD, check: CHECK}",
    "transient": "transient: {t_end: 0.1, dt: 0.01, loads: [{point: P@q1, amplitude: 1}], "
                 "outputs: [P@q1], method: METHOD, check: CHECK}",
}


def message(text: str, overrides: tuple[str, ...] = ()) -> str:
    with pytest.raises(CaseError) as info:
        parse_case(text, "c.yaml", ".", overrides)
    return str(info.value)


def case(kind: str, method: str, check: str, extra: str = "") -> str:
    block = ANALYSES[kind].replace("METHOD", method).replace("CHECK", check)
    text = THREE_DOF + f"analysis:\n  {block}\n" + extra
    if kind == "base_frf":  # the base moves a grounded support
        text = text.replace("constraints:\n", "constraints:\n  - {name: g, terms: {P@q3: 1}}\n")
    return text


@pytest.mark.parametrize("kind", sorted(ANALYSES))
def test_a_check_naming_the_method_is_refused(kind):
    assert message(case(kind, "null-space", "[generalized-inverse, null-space]")) == (
        f"c.yaml: analysis.{kind}.check[1]: a formulation does not check itself: null-space is "
        f"the method; name another formulation or leave it out, got 'null-space'")


@pytest.mark.parametrize("kind", sorted(ANALYSES))
def test_a_check_named_twice_is_refused(kind):
    twice = "[generalized-inverse, generalized-inverse]"
    assert message(case(kind, "null-space", twice)) == (
        f"c.yaml: analysis.{kind}.check[1]: a check named twice (each runs once), got "
        f"'generalized-inverse'")


@pytest.mark.parametrize("kind", sorted(ANALYSES))
def test_distinct_checks_other_than_the_method_are_taken(kind):
    other = "modal" if kind == "transient" else "kkt"
    parsed = parse_case(case(kind, "null-space", f"[{other}, generalized-inverse]"), "c.yaml")
    assert getattr(parsed.analysis, kind).check == [other, "generalized-inverse"]


def test_a_method_set_on_the_command_line_that_the_checks_name_is_refused():
    text = case("modes", "generalized-inverse", "[kkt]")
    assert "check[0]: a formulation does not check itself: kkt is the method" in message(
        text, ("analysis.modes.method=kkt",))


def test_each_check_asked_for_runs_and_agrees(tmp_path):
    """The checks named are the checks computed (the refusal above is the only way one is
    left out): every one has its agreement, within the tolerance."""
    import substruct

    text = case("frf", "generalized-inverse", "[null-space, kkt]")
    result = substruct.run_case(substruct.load_case(text))
    assert sorted(result.frf.agreement) == ["kkt", "null-space"]
    assert max(result.frf.agreement.values()) < 1e-12


TRANSIENT = THREE_DOF + """analysis:
  transient:
    t_end: 1.0
    dt: 0.01
    loads: [{point: P@q1, amplitude: 1, shape: half-sine, duration: 0.1}]
    outputs: [P@q1]
"""


@pytest.mark.parametrize("setting", [(), ("analysis.transient.check=[null-space]",)])
def test_modal_count_without_the_modal_form_is_refused(setting):
    assert message(TRANSIENT, ("analysis.transient.modal_count=2", *setting)) == (
        "c.yaml: analysis.transient.modal_count: the modes of the modal form, which this run "
        "does not use: give method: modal or check: [modal], or leave modal_count out (set on "
        "the command line), got 2")


@pytest.mark.parametrize("setting", ["analysis.transient.check=[modal]",
                                     "analysis.transient.method=modal"])
def test_modal_count_with_the_modal_form_is_taken(setting):
    parsed = parse_case(TRANSIENT, "c.yaml", ".", ("analysis.transient.modal_count=2", setting))
    assert parsed.analysis.transient.modal_count == 2


@pytest.mark.parametrize("every,field_every", [(5, 7), (2, 3), (4, 2)])
def test_field_every_that_the_recorded_steps_do_not_hold_is_refused(every, field_every):
    assert message(TRANSIENT, (f"analysis.transient.every={every}",
                               f"analysis.transient.field_every={field_every}")) == (
        f"c.yaml: analysis.transient.field_every: the fields are kept at recorded steps: a "
        f"multiple of every ({every}), or 0 (set on the command line), got {field_every}")


@pytest.mark.parametrize("every,field_every", [(5, 10), (3, 3), (1, 7), (5, 0)])
def test_the_fields_are_kept_every_field_every_steps(every, field_every):
    import substruct

    text = TRANSIENT + f"    every: {every}\n    field_every: {field_every}\n"
    result = substruct.run_case(substruct.load_case(text))
    steps = 100  # t_end / dt
    want = [0.01 * k for k in range(0, steps + 1, field_every)] if field_every else []
    np.testing.assert_allclose(result.transient.snapshot_t, want, rtol=0, atol=1e-12)


def test_export_uff_refuses_transient(tmp_path, capsys):
    case_file = tmp_path / "c.yaml"
    case_file.write_text(case("modes", "generalized-inverse", "[kkt]"))
    assert cli.main(["run", str(case_file), "--out", str(tmp_path / "r")]) == 0
    capsys.readouterr()
    out = tmp_path / "u"
    code = cli.main(["export", str(tmp_path / "r" / "three_dof.h5"), "--format", "uff",
                     "--transient", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert err == ("substruct: error: --format uff writes every mode and the receptances: no "
                   "--modes, --variant or --transient\n")
    assert not out.exists() or not any(out.iterdir())


MODAL = THREE_DOF + """analysis:
  frf: {omega: {start: 1, stop: 5, num: 20}, inputs: [P@q1], outputs: [P@q1], method: modal}
"""


@pytest.mark.parametrize("block", ["frf", "random"])
def test_a_modal_sum_takes_a_count_or_a_cutoff_not_both(block):
    text = MODAL if block == "frf" else case("random", "modal", "[]")
    assert message(text, (f"analysis.{block}.modal={{count: 1, cutoff: 3}}",)) == (
        f"c.yaml: analysis.{block}.modal.cutoff: keep the modes up to the cut-off or the "
        f"lowest count (1), not both (set on the command line), got 3.0")
    for modal in ("{count: 1}", "{cutoff: 3}"):
        parse_case(text, "c.yaml", ".", (f"analysis.{block}.modal={modal}",))


@pytest.mark.parametrize("block", ["frf", "random"])
def test_checks_of_a_modal_sum_at_no_frequency_are_refused(block):
    text = MODAL if block == "frf" else case("random", "modal", "[]")
    sets = (f"analysis.{block}.modal={{check_frequencies: 0}}",)
    assert message(text, (*sets, f"analysis.{block}.check=[kkt]")) == (
        f"c.yaml: analysis.{block}.modal.check_frequencies: the checks kkt run at the check "
        f"frequencies: give at least 1, or leave check out to run none (set on the command "
        f"line), got 0")
    parse_case(text, "c.yaml", ".", sets)  # no check at all: the sum alone


def test_the_count_decides_the_modes_summed():
    """With count 1 the modal sum keeps one of the two modes (the second-order residual holds
    the other one's static part only), and its kkt check sees the difference."""
    import substruct
    from substruct.analysis.errors import CheckError

    one = substruct.load_case(MODAL, overrides=["analysis.frf.modal={count: 1}"])
    with pytest.raises(CheckError, match=r"modal: 1 root\(s\)"):
        substruct.run_case(one)
    two = substruct.run_case(substruct.load_case(MODAL,
                                                 overrides=["analysis.frf.modal={count: 2}"]))
    assert max(two.frf.agreement.values()) < 1e-12


STUDY = THREE_DOF.replace("[20, -10, 0]", "[k1, -10, 0]") + """parameters: {k1: 20.0}
analysis:
  modes: {count: 2}
study:
  grid:
    parameters:
      - {parameter: k1, values: [20, 22]}
"""


@pytest.mark.parametrize("key", ["damping_ratios", "mac"])
def test_a_study_keeping_values_of_no_mode_is_refused(key):
    text = STUDY + f"  collect: {{{key}: true}}\n"
    assert message(text) == (f"c.yaml: study.collect.{key}: needs collect.frequencies (the "
                             f"modes whose values are kept), got true")


def test_a_study_keeps_the_damping_ratios_and_mac_of_its_modes(tmp_path):
    """With frequencies: 2 the two modes' damping ratios and MAC are collected: at k1 = 20
    (the case as written) every MAC is 1."""
    import substruct
    from substruct.studies.study_run import run_study

    text = STUDY + "  collect: {frequencies: 2, damping_ratios: true, mac: true}\n"
    study = run_study(substruct.load_case(text))
    assert study.values["damping_ratio"].shape == (2, 2)
    np.testing.assert_allclose(study.values["mac"][0], 1.0, atol=1e-12)


@pytest.mark.parametrize("grid,count", [("{start: 0.1, stop: 5, per_octave: 1000000000}",
                                         5_643_856_190),
                                        ("{start: 0.1, stop: 5, num: 1000000000}", 10**9)])
def test_an_srs_grid_is_counted_before_it_is_built(grid, count, monkeypatch):
    """The size check counts the frequencies; building the grid first allocated 42 GB."""
    import substruct.case.spec_analysis as spec

    def refuse(*args, **kwargs):
        raise AssertionError("the grid was built before its size was checked")

    monkeypatch.setattr(spec.np, "arange", refuse)
    monkeypatch.setattr(spec.np, "geomspace", refuse)
    key = "per_octave" if "per_octave" in grid else "num"
    assert message(TRANSIENT + f"  srs: {{frequencies: {grid}}}\n") == (
        f"c.yaml: analysis.srs.frequencies.{key}: {count:,} frequencies from 0.1 to 5 Hz, at "
        f"most 100,000, got 1000000000")


@pytest.mark.parametrize("per_octave", [1, 3, 12])
def test_an_srs_grid_per_octave_is_a_factor_two_to_the_one_over_n(per_octave):
    srs = parse_case(TRANSIENT + f"  srs: {{frequencies: {{start: 10, stop: 2000, "
                     f"per_octave: {per_octave}}}}}\n", "c.yaml").analysis.srs
    f = srs.frequencies.grid()
    assert len(f) == srs.frequencies.count() == int(np.floor(per_octave * np.log2(200))) + 1
    np.testing.assert_allclose(f[1:] / f[:-1], 2.0 ** (1 / per_octave), rtol=1e-14)
    assert f[0] == 10 and f[-1] <= 2000 < f[-1] * 2.0 ** (1 / per_octave)


@pytest.mark.parametrize("key", ["parameters.k1", "parameters[k1]"])
def test_study_refuses_a_set_of_a_varied_parameter(key, tmp_path, capsys):
    """Every sample sets the parameters the study varies: a --set of one was replaced."""
    case_file = tmp_path / "s.yaml"
    case_file.write_text(STUDY + "  collect: {frequencies: 2}\n")
    out = tmp_path / "out"
    code = cli.main(["study", str(case_file), "--out", str(out), "--set", f"{key}=100"])
    err = capsys.readouterr().err
    assert code == 2
    assert err == (f"substruct: error: {case_file}: parameters.k1: the study varies this "
                   f"parameter: its values replace the one of --set in every sample (leave it "
                   f"out of --set), got '100'\n")
    assert not out.exists() or not any(out.iterdir())


def test_study_takes_a_set_of_a_parameter_it_does_not_vary(tmp_path):
    """--set of another parameter reaches every sample: with m1 = 0.5 the second mode of
    each sample is that of the case run with m1 = 0.5, not the one as written."""
    import substruct
    from substruct.studies.study_run import run_study

    text = STUDY.replace("[1, 0, 0], [0, 2, 0]", "[m1, 0, 0], [0, 2, 0]").replace(
        "parameters: {k1: 20.0}", "parameters: {k1: 20.0, m1: 1.0}") + \
        "  collect: {frequencies: 2}\n"
    plain = run_study(substruct.load_case(text))
    light = run_study(substruct.load_case(text, overrides=["parameters.m1=0.5"]))
    for k, k1 in enumerate([20, 22]):
        ref = substruct.run_case(substruct.load_case(
            text, overrides=["parameters.m1=0.5", f"parameters.k1={k1}"]))
        np.testing.assert_allclose(light.values["frequency"][k], ref.modes.omega, rtol=1e-12)
    assert np.all(np.abs(light.values["frequency"][:, 1] - plain.values["frequency"][:, 1])
                  > 0.5)


def test_compare_refuses_force_without_image(tmp_path, capsys):
    """compare writes one file only, the --image picture: --force alone did nothing."""
    case_file = tmp_path / "c.yaml"
    case_file.write_text(case("modes", "generalized-inverse", "[kkt]"))
    assert cli.main(["run", str(case_file), "--out", str(tmp_path / "r")]) == 0
    capsys.readouterr()
    result = str(tmp_path / "r" / "three_dof.h5")
    assert cli.main(["compare", result, result, "--force"]) == 2
    assert capsys.readouterr().err == (
        "substruct: error: --force replaces the picture of --image, the only file compare "
        "writes: give --image, or leave --force out\n")
    image = tmp_path / "mac.png"
    assert cli.main(["compare", result, result, "--image", str(image), "--force"]) == 0
    assert image.stat().st_size > 0


SOLID = """
name: block
substructures:
  - name: block
    type: solid
    rectangle: {lengths: [1.0, 0.2], divisions: [10, 2]}
    E: 2.1e11
    nu: 0.3
    rho: 7850
    fixed: [xmin]
    reduce: {modes: 4}
analysis:
  modes: {count: 2}
output: {pictures: false}
"""


def test_a_solid_takes_rayleigh_or_modal_damping_not_both():
    sets = ("substructures.block.damping={rayleigh: [0, 1.0e-6]}",
            "substructures.block.reduce.damping={ratio: 0.02}")
    assert message(SOLID, sets) == (
        "c.yaml: substructures.block.reduce.damping: the kept modes' damping replaces the "
        "solid's damping (rayleigh), which would be ignored: give one of the two (without "
        "reduce.damping the Rayleigh damping is projected on the modes) (set on the command "
        "line), got '{...}'")


def test_each_damping_of_a_reduced_solid_is_the_one_used():
    """Modal damping gives every kept mode its ratio; Rayleigh damping projected gives mode
    k the ratio alpha / (2 omega_k) + beta omega_k / 2 (the truncated modes are M- and
    K-orthogonal, so the projection stays diagonal)."""
    import substruct

    def run(*sets):
        return substruct.run_case(substruct.load_case(SOLID, overrides=list(sets))).modes

    modal = run("substructures.block.reduce.damping={ratio: 0.02}")
    np.testing.assert_allclose(modal.damping_ratio, 0.02, rtol=1e-9)
    alpha, beta = 3.0, 2.0e-6
    rayleigh = run(f"substructures.block.damping={{rayleigh: [{alpha}, {beta}]}}")
    w = np.abs(rayleigh.eigenvalues)  # |lambda| = omega_n of each damped mode
    np.testing.assert_allclose(rayleigh.damping_ratio, alpha / (2 * w) + beta * w / 2,
                               rtol=1e-9)


def test_python_m_substruct_is_the_command_line(tmp_path):
    """``python -m substruct`` runs the command (it said there was no ``__main__``): a bad
    --set is its one line and exit code 2."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    case_file = tmp_path / "c.yaml"
    case_file.write_text(case("modes", "generalized-inverse", "[kkt]"))
    env = {**os.environ, "PYTHONPATH": str(root), "OMP_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-m", "substruct", "run", str(case_file), "--out",
                           str(tmp_path / "o"), "--set", "analysis.modes.count=0"],
                          capture_output=True, text=True, env=env, timeout=120)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith(f"substruct: error: {case_file}: analysis.modes.count: ")
    assert done.stderr.count("\n") == 1
