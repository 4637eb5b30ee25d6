"""What a run says while it runs (issue 14): phases on stderr as they start, with sizes and
elapsed time, when asked (SUBSTRUCT_PROGRESS=1) or on a terminal; nothing with --quiet; a
warning before a dense eigen solve whose n^3 estimate is long; the sweep bar drawn by tqdm."""

import io
import re
from pathlib import Path

from substruct import cli
from substruct.cli.progress import DENSE_SECONDS_PER_N3, PhaseLog, ProgressBar, dense_seconds

CASES = Path(__file__).resolve().parent.parent / "cases"
PHASE = re.compile(r"^\[\s*(\d+\.\d) s\] (.*)$")
ARGS = ["--force", "--set", "output.pictures=false"]


def run(capsys, *args):
    capsys.readouterr()
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def test_phases_in_order_with_sizes_and_elapsed_time(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("SUBSTRUCT_PROGRESS", "1")
    code, out, err = run(capsys, "run", CASES / "tapered_rod.yaml", "--out", tmp_path, *ARGS)
    assert code == 0, err
    phases = [PHASE.match(line) for line in err.splitlines() if line.startswith("[")]
    texts = [m.group(2) for m in phases if m]
    assert len(texts) == len(phases) == 9, err
    assert texts[0] == "assembling tapered_rod: 5 substructure(s) (rod, a, b, c, d)"
    assert texts[1] == "model: 10 coordinates, 5 constraint row(s), 14 stiffness nonzeros"
    assert texts[2] == "modes (generalized-inverse): dense eigen solve (10 coordinates)"
    assert texts[5] == ("modes (variant without_eq52) (generalized-inverse): dense eigen "
                        "solve (10 coordinates)")
    assert texts[8] == "receptances: 200 frequencies, 3 output(s) x 1 input(s), 10 coordinates"
    times = [float(m.group(1)) for m in phases if m]
    assert times == sorted(times)
    # the phases come before the sweep's own line, and before the table on stdout
    assert err.index("receptances:") < err.index("FRF generalized-inverse: 200 frequencies")
    assert out.startswith("tapered_rod: 10 coordinates")


def test_no_phases_when_quiet_or_not_on_a_terminal(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("SUBSTRUCT_PROGRESS", raising=False)
    code, _, err = run(capsys, "run", CASES / "three_dof_frf.yaml", "--out", tmp_path, *ARGS)
    assert code == 0 and "[" not in err  # stderr is captured, not a terminal
    monkeypatch.setenv("SUBSTRUCT_PROGRESS", "1")
    code, out, err = run(capsys, "run", CASES / "three_dof_frf.yaml", "--out", tmp_path,
                         "--quiet", *ARGS)
    assert (code, out, err) == (0, "", "")


def test_warning_before_a_slow_dense_solve():
    stream = io.StringIO()
    log = PhaseLog(stream, show=False)
    log("dense-eigen", "modes (kkt): dense eigen solve", 200)  # 1.4 s: no warning
    assert stream.getvalue() == ""
    log("dense-eigen", "modes (kkt): dense eigen solve", 1443)
    # the 1443-coordinate solid of the issue: 1.7e-7 x 1443^3 = 511 s
    assert dense_seconds(1443) == DENSE_SECONDS_PER_N3 * 1443 ** 3
    assert 500 < dense_seconds(1443) < 520
    assert stream.getvalue().startswith("substruct: warning: dense eigen solve of 1443 "
                                        "coordinates: about 9 min for the generalized-inverse")
    log("dense-eigen", "modes (null-space): dense eigen solve", 1443)  # said once per size
    assert stream.getvalue().count("warning") == 1
    quiet = io.StringIO()
    PhaseLog(quiet, show=False, warn=False)("dense-eigen", "x", 5000)
    assert quiet.getvalue() == ""


def test_sweep_bar_is_drawn_by_tqdm(monkeypatch):
    import tqdm

    made = []
    real = tqdm.tqdm

    def spy(*args, **kwargs):
        made.append(kwargs)
        return real(*args, **kwargs)
    monkeypatch.setattr(tqdm, "tqdm", spy)

    class Tty(io.StringIO):
        def isatty(self):
            return True
    stream = Tty()
    bar = ProgressBar(stream)
    for done in range(10, 101, 10):
        bar(done, 100, "kkt")
    assert len(made) == 1 and made[0]["total"] == 100
    assert stream.getvalue().endswith("FRF kkt                  [" + "#" * 30 + "] 100/100\n")
