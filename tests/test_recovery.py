"""Output transformation matrices of superelements: a frame reduced by substruct's Craig-Bampton
carries its DTM (the interior rows of the transformation T) and an ATM (the same rows acting
on accelerations) in OP4; coupled to a second frame, the recovered interior responses are
checked against the interior of the unreduced coupled model under the same load: exactly for
the static state, to the reduction's error in modes and in time."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from substruct.case.loader import CaseError, load_case
from substruct.io.hdf5 import load, save
from substruct.io.op4 import write_op4
from substruct.models.beam import Material, Section
from substruct.models.craig_bampton import craig_bampton
from substruct.models.frame import FRAME_COMPONENTS, Beam, frame
from substruct.run.runner import run_case

SEC = Section(A=2.85e-3, Iy=1.94e-5, Iz=1.42e-6, J=7.0e-8)
MAT = Material(E=2.1e11, G=8.1e10, rho=7850.0)
NODES_A = {1: (0.0, 0.0, 0.0), 2: (1.5, 0.0, 0.0), 3: (3.0, 0.0, 0.0)}
NODES_B = {10: (3.0, 0.0, 0.0), 11: (3.0, 2.0, 0.5)}
BOUNDARY_A = (1, 3)


def _frames():
    a = frame("a", NODES_A, [Beam(m, SEC, MAT, (0, 0, 1), divisions=6)
                             for m in ((1, 2), (2, 3))])
    b = frame("b", NODES_B, [Beam((10, 11), SEC, MAT, (0, 0, 1), divisions=6)])
    return a, b


def _dof_rows(labels) -> np.ndarray:
    """``grid, component`` of frame labels ``g:ux``; ``eta<k>`` as modal rows ``0, 0``."""
    out = []
    for lab in labels:
        if lab.startswith("eta"):
            out.append((0, 0))
        else:
            g, c = lab.split(":")
            out.append((int(g), FRAME_COMPONENTS.index(c) + 1))
    return np.array(out, dtype=float)


def _transformation(a, red) -> np.ndarray:
    """``T`` of the reduction: ``row_full(p) @ T = row_reduced(p)`` for each coordinate."""
    return np.vstack([red.row(lab).toarray().ravel() for lab in a.dof_labels])


def _write_models(tmp: Path, modes: int) -> list[str]:
    """a_full.npz, b_full.npz (unreduced), a_cb.op4 (Craig-Bampton of a with its DTM, an ATM
    equal to it, the DTM's row map DTMROWS and the DOF map DOFS); returns the labels of the
    interior coordinates of a (the DTM rows)."""
    a, b = _frames()
    for sub, name in ((a, "a_full"), (b, "b_full")):
        np.savez(tmp / f"{name}.npz", M=sub.M.toarray(), K=sub.K.toarray(),
                 DOFS=_dof_rows(sub.dof_labels))
    bnd = [k for k, lab in enumerate(a.dof_labels) if int(lab.split(":")[0]) in BOUNDARY_A]
    interior = np.setdiff1d(np.arange(a.n_dof), bnd)
    red = craig_bampton(a, bnd, modes)
    dtm = _transformation(a, red)[interior]
    rows = [a.dof_labels[i] for i in interior]
    write_op4(tmp / "a_cb.op4", {"MAA": red.M.toarray(), "KAA": red.K.toarray(), "DTM": dtm,
                                  "ATM": dtm, "DTMROWS": _dof_rows(rows),
                                  "DOFS": _dof_rows(red.dof_labels)}, binary=True)
    return rows


CONNECT = "\n".join(f"  - [a@3:{c}, b@10:{c}]" for c in FRAME_COMPONENTS)
CLAMP = "\n".join(f"  - {{name: c{c}, terms: {{a@1:{c}: 1}}}}" for c in FRAME_COMPONENTS)


def _case(tmp: Path, reduced: bool, outputs: list[str], modes: int = 10,
          extra: str = "", transient: bool = True) -> Path:
    if reduced:
        a = ("{name: a, type: superelement, file: a_cb.op4, M: MAA, K: KAA, dofs: {key: DOFS},"
             " recovery: [{name: dtm, matrix: DTM, labels: {key: DTMROWS}}, "
             "{name: atm, matrix: ATM, of: acceleration, labels: {key: DTMROWS}}" + extra +
             "]}")
    else:
        a = "{name: a, type: superelement, file: a_full.npz, M: M, K: K, dofs: {key: DOFS}}"
    out = ", ".join(f'"{o}"' for o in outputs)
    tr = f"""  transient:
    t_end: 0.04
    dt: 2.0e-4
    initial: static
    loads: [{{point: b@11:uz, amplitude: 1000.0, shape: harmonic, omega: 300.0}},
            {{point: b@11:ux, amplitude: -400.0, shape: harmonic, omega: 700.0}}]
    outputs: [{out}]
""" if transient else ""
    text = f"""name: {'reduced' if reduced else 'full'}
substructures:
  - {a}
  - {{name: b, type: superelement, file: b_full.npz, M: M, K: K, dofs: {{key: DOFS}}}}
connections:
{CONNECT}
constraints:
{CLAMP}
analysis:
  modes: {{count: {modes}, method: generalized-inverse}}
{tr}"""
    path = tmp / f"{'reduced' if reduced else 'full'}.yaml"
    path.write_text(text)
    return path


def _runs(tmp: Path, modes: int, points: list[str]):
    rows = _write_models(tmp, modes)
    full = run_case(load_case(_case(tmp, False, [f"a@{lab}" for lab in rows] + points)))
    red = run_case(load_case(_case(tmp, True, points)))
    return rows, full, red


PART = [f"a@mode:{k}" for k in range(1, 25)] + [f"a@{g}:{c}" for g in BOUNDARY_A
                                                 for c in FRAME_COMPONENTS]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The unreduced model (interior of a as outputs) and its reductions by 6 and 24 modes
    (every coordinate of the reduced a as outputs too)."""
    out = {}
    for g in (6, 24):
        tmp = tmp_path_factory.mktemp(f"cb{g}")
        rows = _write_models(tmp, g)
        part = [p for p in PART if not p.startswith("a@mode:") or int(p[7:]) <= g]
        full = run_case(load_case(_case(tmp, False, [f"a@{lab}" for lab in rows] +
                                        ["b@11:uz"])))
        red = run_case(load_case(_case(tmp, True, part + ["b@11:uz"])))
        out[g] = (tmp, rows, full, red, part)
    return out


def test_recovered_rows_are_the_matrices_times_the_part(runs) -> None:
    """DTM history = DTM x(t), ATM history = ATM a(t), recovered shapes = DTM phi, with x, a
    the part's recorded coordinates (to rounding: the same products)."""
    tmp, rows, _, red, part = runs[6]
    dtm_rec, atm_rec = red.recovery
    # the part's coordinates in the DOF map's order: modes, then boundary grids
    x, a = red.transient.displacement[:, :len(part)], red.transient.acceleration[:, :len(part)]
    from substruct.case.op4 import read_op4
    D = read_op4(tmp / "a_cb.op4", ["DTM"])["DTM"].dense()
    np.testing.assert_allclose(dtm_rec.history, x @ D.T, rtol=0,
                               atol=1e-12 * np.abs(dtm_rec.history).max())
    np.testing.assert_allclose(atm_rec.history, a @ D.T, rtol=0,
                               atol=1e-12 * np.abs(atm_rec.history).max())
    blk = slice(int(red.model.offsets[0]), int(red.model.offsets[1]))
    np.testing.assert_allclose(dtm_rec.modes, D @ red.modes.shapes[blk], rtol=0,
                               atol=1e-12 * np.abs(dtm_rec.modes).max())
    lam2 = (red.modes.eigenvalues ** 2).real
    np.testing.assert_allclose(atm_rec.modes, dtm_rec.modes * lam2, rtol=0,
                               atol=1e-12 * np.abs(atm_rec.modes).max())
    assert dtm_rec.labels == rows and atm_rec.of == ("acceleration",)


def _cond_tolerance(tmp: Path) -> float:
    """``n eps cond(K)`` of the unreduced coupled model's stiffness held at the clamp: the
    rounding of a static solve (the static state is otherwise exact)."""
    a, b = _frames()
    K = a.K.toarray()[6:, 6:]
    return K.shape[0] * np.finfo(float).eps * np.linalg.cond(K)


def test_static_state_recovered_exactly(runs) -> None:
    """Initial state static under the loads at t = 0: the constraint modes hold the exact
    interior of a static load on the boundary, so the DTM recovers the unreduced interior to
    rounding, whatever the number of modes kept."""
    for g, (tmp, rows, full, red, _) in runs.items():
        n = len(rows)
        yf, yr = full.transient.displacement[0, :n], red.recovery[0].history[0]
        err = np.abs(yr - yf).max() / np.abs(yf).max()
        assert err < _cond_tolerance(tmp), (g, err)


def _mode_error(full, red, rows) -> tuple[np.ndarray, np.ndarray]:
    """Per elastic mode: the relative eigenvalue error and the error of the recovered interior
    shape (sign matched)."""
    n = len(rows)
    k = 4
    lf, lr = full.modes.omega[:k] ** 2, red.modes.omega[:k] ** 2
    blk = slice(int(full.model.offsets[0]), int(full.model.offsets[1]))
    labels = [lab.split(".", 1)[1] for lab in full.model.dof_labels[blk]]
    pos = [labels.index(r) for r in rows]
    shape_f = full.modes.shapes[blk][pos][:, :k].real
    shape_r = red.recovery[0].modes[:, :k].real
    sign = np.sign(np.sum(shape_f * shape_r, axis=0))
    err = np.abs(shape_r * sign - shape_f).max(axis=0) / np.abs(shape_f).max(axis=0)
    assert n == shape_f.shape[0]
    return (lr - lf) / lf, err


def test_recovered_modes_converge_like_the_eigenvalues(runs) -> None:
    """The eigenvalue error of a Rayleigh-Ritz reduction is of second order in the shape error
    (|dlambda| / lambda ~ |e|^2): the recovered interior shape errs by about the square root
    of the eigenvalue error, and both fall as modes are added."""
    errors = {}
    for g, (tmp, rows, full, red, _) in runs.items():
        dl, es = _mode_error(full, red, rows)
        rounding = _cond_tolerance(tmp)
        assert np.all(dl > -rounding)  # an upper bound (Rayleigh-Ritz), to rounding
        assert np.all(es <= 10 * np.sqrt(np.abs(dl) + rounding)), (g, dl, es)
        errors[g] = es
    assert np.all(errors[24] < errors[6] / 10)


def test_transient_recovery_converges(runs) -> None:
    """Interior displacement of the unreduced model in time against the DTM recovery: the
    error falls with the modes kept (6: 7e-5, 24: 8e-7 of the peak as measured), and the ATM
    likewise for the accelerations."""
    err = {}
    for g, (_, rows, full, red, _) in runs.items():
        n = len(rows)
        for k, what in ((0, "displacement"), (1, "acceleration")):
            yf = getattr(full.transient, what)[:, :n]
            err[g, what] = np.abs(red.recovery[k].history - yf).max() / np.abs(yf).max()
    assert err[24, "displacement"] < err[6, "displacement"] / 20
    assert err[24, "acceleration"] < err[6, "acceleration"] / 10
    assert err[24, "displacement"] < 1e-5


def test_peaks_summary_and_file(runs, tmp_path: Path) -> None:
    """Peaks are the extremes of the history at their first instants; the result file keeps
    the recovery (read back equal) and the summary prints the peaks table."""
    from substruct.cli.summary import print_summary, summary_json

    _, rows, _, red, _ = runs[6]
    rec = red.recovery[0]
    p = rec.peaks()
    j = int(np.argmax(rec.history[:, 0]))
    assert p.max[0] == rec.history[j, 0] and p.t_max[0] == rec.t[j]
    assert p.min[3] == rec.history[:, 3].min()
    save(red, tmp_path / "r.h5")
    back = load(tmp_path / "r.h5")
    assert [r.title for r in back.recovery] == ["a.dtm", "a.atm"]
    for x, y in zip(red.recovery, back.recovery):
        assert x.labels == y.labels and x.of == y.of
        assert np.array_equal(x.history, y.history) and np.array_equal(x.modes, y.modes)
    out = io.StringIO()
    print_summary(back, out)
    text = out.getvalue()
    assert f"recovery a.dtm (displacement): {len(rows)} row(s), 10 mode shape(s)" in text
    big = int(np.argmax(np.abs(p.extreme())))
    width = max(5, max(map(len, rows)))
    assert f"\n    {rows[big]:<{width}s}  {p.max[big]:12.5g}  {p.t_max[big]:10.4g}" in text
    assert summary_json(back)["recovery"][1]["of"] == ["acceleration"]


@pytest.mark.parametrize("extra,message", [
    (", {name: dtm, matrix: DTM}", r"recovery\[2\]\.name: a recovery name is given twice"),
    (", {name: x, matrix: DTM, of: [acceleration, displacement]}", r"recovery\.x\.matrix: "
     r"matrix 'DTM' must have 2 x 18 columns .* is 66 x 18"),
    (", {name: x, matrix: DTM, labels: [p, q]}", r"recovery\.x\.labels: 2 labels for the "
     r"\d+ rows"),
    (", {name: x, matrix: DTM, of: [displacement, displacement]}", r"recovery\.x\.of: each "
     r"history once"),
    (", {name: x, matrix: NOPE}", r"substructures\.a\.file: a_cb\.op4: no matrix 'NOPE'"),
    (", {name: x, matrix: DTM, of: strain}", r"recovery\.x\.of"),
])
def test_bad_recovery(tmp_path: Path, extra: str, message: str) -> None:
    _write_models(tmp_path, 6)
    with pytest.raises(CaseError, match=message):
        load_case(_case(tmp_path, True, ["b@11:uz"], extra=extra))


def test_compare_two_runs_peaks(runs, tmp_path: Path, capsys) -> None:
    """``substruct compare`` of the reductions by 6 and 24 modes: the modes and a table of the
    recovered peaks, matched by recovery and row, largest change first."""
    import json

    from substruct import cli

    save(runs[6][3], tmp_path / "a.h5")
    save(runs[24][3], tmp_path / "b.h5")
    assert cli.main(["compare", str(tmp_path / "a.h5"), str(tmp_path / "b.h5"), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    rows = data["peaks"]
    assert len(rows) == 2 * len(runs[6][1])
    first = rows[0]
    k = runs[6][1].index(first["row"])
    rec_a = runs[6][3].recovery[0 if first["recovery"] == "a.dtm" else 1]
    rec_b = runs[24][3].recovery[0 if first["recovery"] == "a.dtm" else 1]
    ea, eb = rec_a.peaks().extreme()[k], rec_b.peaks().extreme()[k]
    assert first["change"] == pytest.approx((abs(eb) - abs(ea)) / abs(ea), rel=1e-12)
    assert abs(first["change"]) >= max(abs(r["change"]) for r in rows[1:] if r["change"])
    assert cli.main(["compare", str(tmp_path / "a.h5"), str(tmp_path / "b.h5")]) == 0
    text = capsys.readouterr().out
    assert f"recovered peaks ({len(rows)} quantities in both; largest change first):" in text
    assert f"  {first['recovery']}@{first['row']}" in text


def _npz_case(tmp: Path, labels: np.ndarray, rows: int = 2) -> Path:
    np.savez(tmp / "se.npz", K=np.array([[2.0, -1.0], [-1.0, 2.0]]), M=np.eye(2),
             R=np.ones((rows, 2)), L=labels)
    (tmp / "case.yaml").write_text("""name: t
substructures:
  - {name: se, type: superelement, file: se.npz, M: M, K: K, dofs: [[1, "1"], [2, "1"]],
     free: false, recovery: [{name: dtm, matrix: R, of: displacement, labels: {key: L}}]}
analysis:
  modes: {count: 2}
""")
    return tmp / "case.yaml"


@pytest.mark.parametrize("labels", [np.array([[1, 1], [2, 1]]) + 0.5j,  # was a TypeError
                                    np.array([[True, True], [True, False]])])  # was "1:ux"
def test_label_member_of_numbers_that_are_not_ids(tmp_path: Path, labels) -> None:
    with pytest.raises(CaseError, match=rf"recovery\.dtm\.labels\.key: a label member is n x 2 "
                       rf"\(grid, component\) or an array of strings, got {labels.dtype} "
                       rf"entries"):
        load_case(_npz_case(tmp_path, labels))
    case = load_case(_npz_case(tmp_path, np.array([[1, 1], [2, 3]])))
    assert case.substructures[0].recovery[0].row_labels() == ["1:ux", "2:uz"]


def test_label_named_twice_found_in_one_pass(tmp_path: Path) -> None:
    """200,000 labels, the last a copy of the first: the copy was searched for by comparing
    each label with all those before it (2e10 comparisons, minutes); now one pass."""
    import time

    n = 200_000
    labels = np.array([f"r{k}" for k in range(n)])
    labels[-1] = "r0"
    path = _npz_case(tmp_path, labels, rows=n)
    start = time.perf_counter()
    with pytest.raises(CaseError, match=r"recovery\.dtm\.labels: label 'r0' names two rows"):
        load_case(path)
    assert time.perf_counter() - start < 30.0
