"""The substruct command end to end: every case runs, bad input is one line and exit code 2,
--force and --set, the paper's numbers as printed, info and export, the installed entry point."""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from substruct import cli
from substruct.cli.progress import ProgressBar
from substruct.case.loader import load_case
from substruct.run.runner import run_case
from cli_helpers import run, assert_one_line_error

CASES = Path(__file__).resolve().parent.parent / "cases"
ALL = sorted(CASES.glob("*.yaml"))
NO_PICTURES = ["--set", "output.pictures=false"]

# eq (40) as printed
H40 = [["0.0246-0.0295i", "0.0082-0.0098i", "-0.0082+0.0098i"],
       ["0.0082-0.0098i", "0.3361-0.0033i", "0.1639+0.0033i"],
       ["-0.0082+0.0098i", "0.1639+0.0033i", "0.0861-0.0033i"]]
TABLE1_WITH = [21.7, 54.8, 74.2, 83.7, 97.1]          # the printed "0" is a spurious root
TABLE1_WITHOUT = [21.7, 54.8, 59.0, 83.7, 97.1, 135.0]


def mode_table(text: str) -> list[list[float]]:
    """The omega column of each mode table printed by ``substruct run``."""
    tables, current = [], None
    for line in text.splitlines():
        if "omega (rad/s)" in line:
            current = []
            tables.append(current)
        elif current is not None and re.match(r"\s+\d+\s+[-\d.]+\s", line):
            current.append(float(line.split()[1]))
        else:
            current = None
    return tables


# --------------------------------------------------------------------- every case runs


@pytest.mark.parametrize("path", ALL, ids=lambda p: p.stem)
def test_every_case_runs_and_its_result_round_trips(path, tmp_path, capsys):
    from substruct.io import hdf5 as results
    code, out, err = run(capsys, "run", path, "--out", tmp_path, "--json", "--quiet",
                         *NO_PICTURES)
    assert code == 0, err
    summary = json.loads(out)
    h5 = tmp_path / f"{path.stem}.h5"
    assert summary["files"] == [str(h5)] and h5.is_file()
    back = results.load(h5)
    assert back.case_name == path.stem
    # the effective case: the file with the override applied, the override listed on top
    assert "# --set output.pictures=false" in back.case_yaml
    effective = yaml.safe_load(back.case_yaml)
    assert effective["output"]["pictures"] is False
    assert effective["substructures"] == yaml.safe_load(path.read_text())["substructures"]
    if "modes" in summary:
        np.testing.assert_array_equal(back.modes.omega, summary["modes"]["omega"])
        assert back.modes.residual.max() < 1e-8
        assert all(v < 1e-8 for v in back.modes.agreement.values())
    if "frf" in summary:
        assert back.frf.constraint_residual < 1e-10
        assert all(v < 1e-8 for v in back.frf.agreement.values())
    assert back.attrs["substruct_version"] and back.attrs["created"]
    assert list(tmp_path.iterdir()) == [h5]


def test_pictures_are_written_beside_the_result(tmp_path, capsys):
    code, out, err = run(capsys, "run", CASES / "three_dof_frf.yaml", "--out", tmp_path,
                         "--quiet")
    assert code == 0, err
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["three_dof_frf.h5", "three_dof_frf_frf.png", "three_dof_frf_modes.png"]
    import matplotlib.image
    for png in tmp_path.glob("*.png"):
        assert matplotlib.image.imread(png)[..., :3].std() > 0.01  # not blank


# ----------------------------------------------------------------- the paper, as printed


def test_three_dof_prints_eq40(tmp_path, capsys):
    code, out, err = run(capsys, "run", CASES / "three_dof_frf.yaml", "--out", tmp_path,
                         *NO_PICTURES)
    assert code == 0, err
    rows = {line.split()[0]: line.split()[1:] for line in out.splitlines()
            if line.strip().startswith("P@q")}
    assert [rows["P@q1"], rows["P@q2"], rows["P@q3"]] == H40
    assert "agreement with check formulations" in out and "null-space" in out


def test_nonhomogeneous_case_satisfies_constraint_41(tmp_path, capsys):
    from substruct.io import hdf5 as results
    code, _, err = run(capsys, "run", CASES / "three_dof_frf_nonhomogeneous.yaml", "--out",
                       tmp_path, "--quiet", *NO_PICTURES)
    assert code == 0, err
    H = results.load(tmp_path / "three_dof_frf_nonhomogeneous.h5").frf.H[0]
    np.testing.assert_allclose(H[0] + 2 * H[2], [1.0, 1.0, 3.0], atol=1e-12)  # eq (41)


def test_table1_as_printed(tmp_path, capsys):
    code, out, err = run(capsys, "run", CASES / "tapered_rod_table1.yaml", "--out", tmp_path,
                         *NO_PICTURES)
    assert code == 0, err
    with_52, without_52 = mode_table(out)
    assert np.round(with_52, 1).tolist() == TABLE1_WITH
    assert np.round(without_52, 1).tolist() == TABLE1_WITHOUT
    assert "spurious roots set aside: 10" in out and "variant without_eq52 (drops eq52)" in out


def test_set_changes_the_answer(tmp_path, capsys):
    def omegas(*extra):
        code, out, err = run(capsys, "run", CASES / "tapered_rod_table1.yaml", "--out",
                             tmp_path, "--json", "--quiet", "--force", *NO_PICTURES, *extra)
        assert code == 0, err
        return json.loads(out)["variants"]["without_eq52"]["omega"]
    base = omegas()
    stiffer = omegas("--set", "substructures.c.stiffness=14000")
    assert np.round(base, 1).tolist() == TABLE1_WITHOUT
    assert not np.allclose(base, stiffer)
    # the same through the Python API
    case = load_case(CASES / "tapered_rod_table1.yaml", ["substructures.c.stiffness=14000"])
    np.testing.assert_allclose(run_case(case).variants["without_eq52"].omega, stiffer,
                               rtol=1e-12)


# ---------------------------------------------------------------- bad input: exit code 2


def _write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize("case_text, extra, fragments", [
    ("name: x\nsubstructures: [\n", [], ["invalid YAML", "line 3"]),
    ((CASES / "tapered_rod_table1.yaml").read_text().replace("length: 200", "lenght: 200"), [],
     ["substructures.rod.lenght: unknown key"]),
    ((CASES / "tapered_rod_table1.yaml").read_text(), ["--set", "substructures.c.stiffness=-1"],
     ["substructures.c.stiffness: must be > 0 (set on the command line), got -1"]),
    ((CASES / "tapered_rod_table1.yaml").read_text(), ["--set", "connections[1]=[rod@300, b]"],
     ["connections[1][0]: point is not on rod 'rod' [0, 200], got 'rod@300'"]),
    ((CASES / "tapered_rod_table1.yaml").read_text(), ["--set", "nosuch.key"],
     ["--set nosuch.key: expected key.path=value"]),
    ((CASES / "three_dof_frf.yaml").read_text(),
     ["--set", "substructures.P.M=[[1, 2, 0], [2, 1, 0], [0, 0, 4]]"],
     ["substructures.P.M: must be positive semidefinite: smallest eigenvalue -1"]),
])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys, case_text, extra,
                                                         fragments):
    case = _write(tmp_path, "case.yaml", case_text)
    out_dir = tmp_path / "out"
    assert_one_line_error(*run(capsys, "run", case, "--out", out_dir, *extra),
                          f"{case}: ", *fragments)
    assert not out_dir.exists()


@pytest.mark.parametrize("args, fragment", [
    (["run", "nope.yaml"], "nope.yaml: no such case file"),
    (["run"], "the following arguments are required: CASE.yaml"),
    ([], "choose a command: run, converge, info, export, compare or study"),
    (["frobnicate"], "invalid choice: 'frobnicate'"),
    (["run", CASES / "three_dof_frf.yaml", "--bogus"], "unrecognized arguments: --bogus"),
    (["info", "nope.h5"], "nope.h5: no such file"),
    (["info", CASES / "three_dof_frf.yaml"], "not a substruct result"),
    (["export", "x.h5"], "the following arguments are required: --format"),
    (["export", "x.h5", "--format", "stl"], "invalid choice: 'stl'"),
])
def test_usage_errors(tmp_path, capsys, monkeypatch, args, fragment):
    monkeypatch.chdir(tmp_path)
    assert_one_line_error(*run(capsys, *args), fragment)
    assert list(tmp_path.iterdir()) == []


def test_out_must_be_a_writable_directory(tmp_path, capsys):
    blocker = _write(tmp_path, "file", "")
    assert_one_line_error(*run(capsys, "run", CASES / "three_dof_frf.yaml", "--out", blocker),
                          "exists and is not a directory")
    assert_one_line_error(*run(capsys, "run", CASES / "three_dof_frf.yaml", "--out",
                               blocker / "sub"), "is not a directory")


def test_force(tmp_path, capsys):
    h5 = tmp_path / "three_dof_frf.h5"
    args = ["run", CASES / "three_dof_frf.yaml", "--out", tmp_path, "--quiet", *NO_PICTURES]
    assert run(capsys, *args)[0] == 0
    before = h5.read_bytes()
    assert_one_line_error(*run(capsys, *args), f"{h5} exists; use --force to overwrite it")
    assert h5.read_bytes() == before
    os.utime(h5, (0, 0))
    code, _, err = run(capsys, *args, "--force", "--set", "parameters.k3=40")
    assert code == 0, err
    assert h5.stat().st_mtime > 0
    from substruct.io import hdf5 as results
    assert "parameters.k3=40" in results.load(h5).case_yaml
    assert sorted(p.name for p in tmp_path.iterdir()) == ["three_dof_frf.h5"]


def test_internal_error_is_exit_1_with_traceback(tmp_path, capsys, monkeypatch):
    import substruct.run.runner

    def broken(*args, **kwargs):
        raise RuntimeError("a bug")
    monkeypatch.setattr(substruct.run.runner, "run_case", broken)
    code, _, err = run(capsys, "run", CASES / "three_dof_frf.yaml", "--out", tmp_path)
    assert code == 1 and "Traceback" in err and "RuntimeError: a bug" in err


# -------------------------------------------------------- progress, info, export, --json


def test_progress_on_long_sweeps_unless_quiet(tmp_path, capsys, monkeypatch):
    args = ["run", CASES / "tapered_rod.yaml", "--out", tmp_path, "--force", *NO_PICTURES]
    monkeypatch.setenv("SUBSTRUCT_PROGRESS", "1")
    code, out, err = run(capsys, *args)
    assert code == 0
    assert "FRF generalized-inverse: 200 frequencies done" in err and "FRF kkt" in err
    assert "rod@200 / rod@200: max |H| =" in out
    code, out, err = run(capsys, *args, "--quiet")
    assert code == 0 and out == "" and "FRF" not in err
    # off a terminal the sweeps say nothing, as the phases (README, "While it runs")
    for env in ("0", None):
        if env is None:
            monkeypatch.delenv("SUBSTRUCT_PROGRESS")
        else:
            monkeypatch.setenv("SUBSTRUCT_PROGRESS", env)
        code, out, err = run(capsys, *args)
        assert code == 0 and "max |H| =" in out and err == ""


def test_progress_bar_on_a_terminal():
    class Tty:
        text = ""

        def isatty(self):
            return True

        def write(self, s):
            self.text += s

        def flush(self):
            pass
    stream = Tty()
    bar = ProgressBar(stream)
    for done in range(10, 201, 10):
        bar(done, 200, "kkt")
    assert stream.text.count("\r") == 20 and stream.text.endswith("200/200\n")
    assert "[##############################]" in stream.text
    bar(3, 3, "short")  # short sweeps: nothing
    assert stream.text.endswith("200/200\n")


def test_info_and_export(tmp_path, capsys):
    assert run(capsys, "run", CASES / "tapered_rod_table1.yaml", "--out", tmp_path, "--quiet",
               *NO_PICTURES)[0] == 0
    h5 = tmp_path / "tapered_rod_table1.h5"
    code, out, err = run(capsys, "info", h5)
    assert code == 0, err
    assert "substructure c: free-free, 2 coordinate(s)" in out and "constraint: eq52" in out
    assert np.round(mode_table(out)[0], 1).tolist() == TABLE1_WITH
    code, out, _ = run(capsys, "info", h5, "--json")
    assert json.loads(out)["model"]["constraints"][-1] == "eq52"

    code, out, err = run(capsys, "export", h5, "--format", "vtu", "--modes", "1-3", "--out",
                         tmp_path / "vtk")
    assert code == 0, err
    import meshio
    mesh = meshio.read(out.split()[0])
    assert {"mode_1_real", "mode_3_imag"} <= set(mesh.point_data)
    code, out, err = run(capsys, "export", h5, "--format", "xdmf", "--variant", "without_eq52",
                         "--out", tmp_path / "xdmf")
    assert code == 0, err
    assert_one_line_error(*run(capsys, "export", h5, "--format", "vtu", "--modes", "1-9",
                               "--out", tmp_path / "none"), "no mode 6")
    assert_one_line_error(*run(capsys, "export", h5, "--format", "vtu", "--modes", "a-b",
                               "--out", tmp_path / "none"), "--modes")
    assert not (tmp_path / "none").exists()


def test_python_api_is_exported():
    import substruct
    if not hasattr(substruct, "load_case"):
        pytest.skip("substruct/__init__.py does not export load_case/run_case yet")
    assert substruct.load_case is load_case and substruct.run_case is run_case


def test_installed_entry_point(tmp_path):
    exe = Path(sys.executable).parent / "substruct"
    if not exe.exists():
        pytest.skip("the substruct console script is not installed beside this python")
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run([str(exe), "run", str(CASES / "three_dof_frf.yaml"), "--out",
                           str(tmp_path), "--json", *NO_PICTURES], capture_output=True,
                          text=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    H = np.array(json.loads(proc.stdout)["frf"]["H"]["real"])[0]
    assert np.round(H[1, 1], 4) == 0.3361
    proc = subprocess.run([str(exe), "run", str(tmp_path / "missing.yaml")],
                          capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1
