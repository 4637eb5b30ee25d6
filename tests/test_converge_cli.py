"""``substruct converge``: a case file's rod system (spec_from_case), the command end to end,
bad input as one line with exit code 2 and nothing written, --force, progress, --json."""

import io
import json
import os
import re
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest
import yaml

from substruct import cli
from substruct.case.loader import CaseError, load_case
from substruct.studies.convergence import dofs_to_reach
from substruct.studies.levels import StudyLevels
from substruct.builder.rod_system import paper_rod_spec
from substruct.builder.rod_system_case import spec_from_case
from substruct.io.convergence_report import load_h5
from cli_helpers import run, assert_one_line_error

CASES = Path(__file__).resolve().parent.parent / "cases"
ROD = CASES / "tapered_rod.yaml"
#: A small study (a fraction of a second per variant): every series, three levels each.
TINY = "assumed=4,8,16; enriched=2,4,8; p1=8,16,32; p2=4,8,16"


def rod_case(tmp_path, edit=None, name="case.yaml"):
    """``tapered_rod.yaml`` with ``edit(data)`` applied, written to ``tmp_path/name``."""
    data = yaml.safe_load(ROD.read_text())
    if edit is not None:
        edit(data)
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def table_row(text, title, after=""):
    """The numbers of the first row starting with ``title`` after the line ``after``."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if after in line)
    line = next(line for line in lines[start:] if line.strip().startswith(title))
    return [float(v) for v in re.findall(r"-?\d+\.\d+(?:e[-+]\d+)?", line[31:])]


# ------------------------------------------------------------------- the case's system


def test_spec_from_case_is_the_papers_rod():
    spec, g = spec_from_case(load_case(ROD))
    paper = paper_rod_spec()
    assert g == 4 and spec.name == "tapered_rod" and spec.n_modes == 6
    assert (spec.length, spec.support) == (paper.length, paper.support)
    assert spec.attachments == paper.attachments and spec.constraints == paper.constraints
    x = np.linspace(0.0, 200.0, 9)
    np.testing.assert_allclose(spec.EA(x), paper.EA(x), rtol=1e-14)
    np.testing.assert_allclose(spec.m(x), paper.m(x), rtol=1e-14)


def test_spec_from_case_positions_counts_and_no_reduction():
    case = load_case(ROD, ["connections[0]=[rod@L/4, a]", "connections[2]=[rod@x=150, c@boundary]",
                           "constraints.eq52.terms={rod@L/4: 2, rod@L: 3}",
                           "constraints[1]={name: spare, terms: {rod@10: 1}, active: false}",
                           "analysis.modes.count=4", "substructures.rod.reduce=null",
                           "analysis.modes.variants=[]"])
    spec, g = spec_from_case(case)
    assert g is None and spec.n_modes == 4
    assert [a.x for a in spec.attachments] == [50.0, 100.0, 150.0, 200.0]
    assert [c.name for c in spec.constraints] == ["eq52"]  # inactive ones are left out
    assert spec.constraints[0].terms == ((50.0, 2.0), (200.0, 3.0))
    spec, _ = spec_from_case(load_case(ROD, ["analysis.modes=null"]))
    assert spec.n_modes == 6


def _two_rods(data):
    data["substructures"].append(dict(data["substructures"][0], name="rod2"))


def _rod_and_matrices(data):
    data["substructures"].append({"name": "P", "type": "matrices", "M": [[1.0]], "K": [[1.0]]})


def _unattached(data):
    data["connections"] = data["connections"][:3]
    data["analysis"].pop("frf")


@pytest.mark.parametrize("edit, overrides, fragments", [
    (_two_rods, [], ["substructures.rod2.type: a convergence study refines one rod, the case "
                     "has 2 (rod, rod2), got 'rod'"]),
    (_rod_and_matrices, [], ["substructures.P.type: ", "matrices substructure cannot be "
                             "refined, got 'matrices'"]),
    (_unattached, [], ["substructures.d: free-free substructure 'd' is not connected to rod "
                       "'rod'", "got 'd'"]),
    (None, ["constraints.eq52.rhs=0.5"], ["constraints.eq52.rhs: ", "homogeneous", "got 0.5"]),
    (None, ["constraints.eq52.rhs_force={rod@50: 1}"],
     ["constraints.eq52.rhs_force: ", 'got {"rod@50": 1.0}']),
    (None, ["constraints.eq52.terms={rod@50: 1, c@mass: 2}"],
     ["constraints.eq52.terms.c@mass: ", "points of rod 'rod' only, got 'c@mass'"]),
    (None, ["constraints.eq52.terms={rod@50: 1, rod@L/4: -1}"],
     ["constraints.eq52.terms: its terms cancel"]),
    (None, ["connections[2]=[rod@150, c@mass]"],
     ["connections[2][1]: ", "at its boundary", "got 'c@mass'"]),
    (None, ["connections[1]=[rod@100, a]"], ["connections[1][1]: 'a' is connected a second"]),
    (None, ["connections[1]=[rod@100, rod@120, b]"], ["connections[1][1]: a second point of "
                                                      "rod 'rod'"]),
    (None, ["connections[0]=[rod@L/4 + 1000, a]"], ["connections[0][0]: point is not on rod"]),
    (None, ["substructures.rod.reduce.damping={ratio: 0.02}"],
     ["substructures.rod.reduce.damping: ", "modal damping"]),
])
def test_what_the_study_cannot_represent_is_a_case_error(tmp_path, edit, overrides, fragments):
    path = rod_case(tmp_path, edit)
    with pytest.raises(CaseError) as info:
        spec_from_case(load_case(path, overrides))
    message = str(info.value)
    assert message.startswith(f"{path}: ") and "\n" not in message
    for fragment in fragments:
        assert fragment in message, message


# ---------------------------------------------------------------------- end to end


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    """``substruct converge cases/tapered_rod.yaml --levels quick`` (the constrained variant:
    28 levels, a few seconds)."""
    out = tmp_path_factory.mktemp("converge") / "results"
    stdout, stderr = io.StringIO(), io.StringIO()
    with redirect_stdout(stdout), redirect_stderr(stderr):
        code = cli.main(["converge", str(ROD), "--levels", "quick", "--variants", "constrained",
                         "--out", str(out)])
    return code, stdout.getvalue(), stderr.getvalue(), out


def test_quick_study_writes_h5_png_and_prints_the_table(quick):
    code, out, err, folder = quick
    assert code == 0, err
    h5, png = folder / "tapered_rod_convergence.h5", folder / "tapered_rod_convergence.png"
    assert sorted(p.name for p in folder.iterdir()) == [h5.name, png.name]  # no temporaries
    # the file
    result = load_h5(h5)
    assert result.name == "tapered_rod" and result.n_modes == 6
    assert list(result.variants) == ["constrained"]
    v = result.variants["constrained"]
    assert v.label == "with eq52"
    assert list(v.series) == ["assumed", "assumed-g4", "enriched", "fe-p1", "fe-p2"]  # g = 4
    quick_levels = StudyLevels.preset("quick")
    assert tuple(v.series["fe-p2"].level) == quick_levels.fe_p2
    np.testing.assert_allclose(v.series["fe-p1"].rate, 2.0, atol=0.1)
    np.testing.assert_allclose(v.series["fe-p2"].rate, 4.0, atol=0.1)
    np.testing.assert_allclose(abs(v.limit[0]), 31.5586551, rtol=1e-8)  # docs/convergence.md
    # the table, with the rates
    assert out.startswith("Convergence study: tapered_rod")
    assert "== with eq52 ==" in out and "DOFs for worst error <= 1e-06:" in out
    np.testing.assert_allclose(table_row(out, "fitted order (theory 4)", "fe-p2  "),
                               np.round(v.series["fe-p2"].rate, 2))
    np.testing.assert_allclose(table_row(out, "fitted order (theory 2)", "fe-p1  "),
                               np.round(v.series["fe-p1"].rate, 2))
    assert out.rstrip().endswith(f"written: {h5}, {png}")
    # progress (stderr is not a terminal: one line at the end)
    assert err == "converge tapered_rod: 28 levels done\n"
    # the picture: a PNG with something drawn on it
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import matplotlib.image
    img = matplotlib.image.imread(png)
    assert img.shape[0] > 200 and img.shape[1] > 400
    colours = np.unique((img[..., :3] * 255).astype(np.uint8).reshape(-1, 3), axis=0)
    assert len(colours) > 50 and img[..., :3].std() > 0.05


def test_json_summary_and_variants(tmp_path, capsys):
    code, out, err = run(capsys, "converge", ROD, "--levels", TINY + "; g=none", "--variants",
                         "unconstrained,bare", "--out", tmp_path, "--json", "--quiet",
                         "--tol", "1e-3", "--reference", "finest")

    def strict(token):
        raise ValueError(f"not JSON: {token}")
    assert code == 0 and err == ""
    summary = json.loads(out, parse_constant=strict)
    assert summary["name"] == "tapered_rod" and summary["tol"] == 1e-3
    assert summary["attrs"]["reference"] == "finest"
    assert [Path(f).name for f in summary["files"]] == ["tapered_rod_convergence.h5",
                                                       "tapered_rod_convergence.png"]
    assert all(Path(f).exists() for f in summary["files"])
    assert list(summary["variants"]) == ["unconstrained", "bare"]
    series = summary["variants"]["unconstrained"]["series"]
    assert list(series) == ["assumed", "enriched", "fe-p1", "fe-p2"]  # g=none: no fixed-g
    assert series["fe-p2"]["theory_rate"] == 4.0 and series["fe-p2"]["dofs"] == [8, 16, 32]
    # against the finest P2 level, P2 reaches 1e-3 there only, P1 not at all
    assert series["fe-p2"]["dofs_to_reach"] == 32 and series["fe-p1"]["dofs_to_reach"] is None
    saved = load_h5(summary["files"][0]).variants["unconstrained"].series
    for key, s in series.items():
        assert s["dofs_to_reach"] == dofs_to_reach(saved[key], 1e-3)
        np.testing.assert_array_equal(np.array(s["rate"], dtype=float), saved[key].rate)
    assert len(summary["variants"]["bare"]["limit_omega"]) == 6


def test_force_quiet_and_progress_on_a_terminal(tmp_path, capsys, monkeypatch):
    args = ["converge", ROD, "--levels", TINY, "--variants", "constrained", "--out", tmp_path]
    h5, png = tmp_path / "tapered_rod_convergence.h5", tmp_path / "tapered_rod_convergence.png"

    class Tty(io.StringIO):
        def isatty(self):
            return True
    tty = Tty()
    monkeypatch.setattr("sys.stderr", tty)
    assert cli.main([str(a) for a in args]) == 0
    monkeypatch.undo()
    frames = tty.getvalue().split("\r")[1:]
    assert len(frames) > 3 and frames[-1].endswith("15/15\n")
    assert frames[0].startswith("converge with eq52: assumed modes (g = n) 4")
    widths = [len(f.rstrip("\n")) for f in frames]
    assert widths == sorted(widths)  # no frame shorter than the last: \r overwrites it all
    capsys.readouterr()
    before = h5.read_bytes(), png.read_bytes()
    # no --force: refused, nothing touched; also when only one of the two files exists
    assert_one_line_error(*run(capsys, *args), f"{h5} exists; use --force to overwrite it")
    h5.unlink()
    assert_one_line_error(*run(capsys, *args), f"{png} exists; use --force to overwrite it")
    assert not h5.exists() and png.read_bytes() == before[1]
    # --force: both written again; --quiet: nothing on the screen
    os.utime(png, (0, 0))
    code, out, err = run(capsys, *args, "--force", "--quiet")
    assert (code, out, err) == (0, "", "")
    assert h5.exists() and png.stat().st_mtime > 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [h5.name, png.name]
    # a directory in the way is an error even with --force
    png.unlink()
    png.mkdir()
    assert_one_line_error(*run(capsys, *args, "--force"), f"{png} is a directory")


# ---------------------------------------------------------------------- bad input


@pytest.mark.parametrize("case, extra, fragments", [
    ("two_rods", [], ["substructures.rod2.type: a convergence study refines one rod"]),
    (CASES / "three_dof_frf.yaml", [], ["three_dof_frf.yaml: substructures: a convergence "
                                        "study needs one substructure of type rod, the case "
                                        "has none, got [\"matrices\"]"]),
    (ROD, ["--set", "constraints.eq52.rhs=1"], ["constraints.eq52.rhs: "]),
    (ROD, ["--set", "substructures.c.stiffness=-1"],
     ["substructures.c.stiffness: must be > 0 (set on the command line), got -1"]),
    ("nope.yaml", [], ["nope.yaml: no such case file"]),
    (ROD, ["--levels", "cubic=3"], ["--levels: bad item 'cubic=3'"]),
    (ROD, ["--levels", "p1=0"], ["--levels: 0 in 'p1=0' must be positive"]),
    (ROD, ["--levels", "p2=64:8"], ["--levels: empty range '64:8'"]),
    (ROD, ["--levels", "assumed=100000"], ["more than the 1024 functions"]),
    (ROD, ["--levels", "p1=; p2="], ["--levels: no finite-element series"]),
    (ROD, ["--variants", "constrained,sideways"], ["--variants: expected a comma list of "
                                                   "constrained, unconstrained, bare"]),
    (ROD, ["--variants", "constrained", "--set", "constraints.eq52.active=false", "--set",
           "analysis.modes.variants=[]"], ["nothing to study"]),
    (ROD, ["--tol", "0"], ["--tol: must be a positive number, got 0"]),
    (ROD, ["--tol", "x"], ["argument --tol: invalid float value: 'x'"]),
    (ROD, ["--reference", "exact"], ["argument --reference: invalid choice: 'exact'"]),
    (None, [], ["the following arguments are required: CASE.yaml"]),
])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys, monkeypatch, case,
                                                         extra, fragments):
    monkeypatch.chdir(tmp_path)
    if case == "two_rods":
        case = rod_case(tmp_path, _two_rods)
    out_dir = tmp_path / "out"
    args = ["converge"] + ([case] if case is not None else []) + ["--out", out_dir, *extra]
    assert_one_line_error(*run(capsys, *args), *fragments)
    assert not out_dir.exists()


def test_out_must_be_a_writable_directory(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert_one_line_error(*run(capsys, "converge", ROD, "--out", blocker),
                          "--out", "exists and is not a directory")
    assert_one_line_error(*run(capsys, "converge", ROD, "--out", blocker / "sub"),
                          "is not a directory")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_internal_error_is_exit_1_with_traceback(tmp_path, capsys, monkeypatch):
    import substruct.studies.convergence as convergence

    def broken(*args, **kwargs):
        raise RuntimeError("a bug")
    monkeypatch.setattr(convergence, "convergence_study", broken)
    code, _, err = run(capsys, "converge", ROD, "--out", tmp_path, "--quiet")
    assert code == 1 and "Traceback" in err and "RuntimeError: a bug" in err


def test_second_writer_into_one_out_is_refused(tmp_path, capsys):
    from substruct.io.file_set import OutputDir

    args = ["converge", ROD, "--levels", TINY, "--variants", "constrained", "--out", tmp_path,
            "--quiet"]
    with OutputDir(tmp_path):  # another writer holds the directory
        code, out, err = run(capsys, *args)
    assert (code, out, err) == (2, "", f"substruct: error: another run is writing {tmp_path}\n")
    assert list(tmp_path.iterdir()) == []
    assert run(capsys, *args)[0] == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tapered_rod_convergence.h5",
                                                         "tapered_rod_convergence.png"]


def test_a_limit_of_one_level_is_not_called_richardson(tmp_path, capsys):
    """One P2 level has no Richardson estimate: the errors are against that level, and the
    table says so (it said 'errors against Richardson' over a row of '-')."""
    code, out, err = run(capsys, "converge", ROD, "--levels", "assumed=4,8; enriched=; p1=8; "
                         "p2=3; g=none", "--variants", "bare", "--out", tmp_path)
    assert code == 0, err
    assert ("limit: fe-p2 n_el=3; errors against the finest level (no Richardson estimate: "
            "the limit series has one level)") in out
    code, out, err = run(capsys, "converge", ROD, "--levels", "assumed=4,8; enriched=; p1=8; "
                         "p2=3,6; g=none", "--variants", "bare", "--out", tmp_path, "--force")
    assert code == 0, err
    assert "limit: fe-p2 n_el=6 (Richardson with n_el=3, order 4); errors against Richardson" in out
