"""Superelements: Craig-Bampton models made by substruct, written as OP4 by our writer, read back
by ``type: superelement`` and coupled, against the same reductions coupled in memory; the
rigid-body mass properties against the unreduced frames; the checks that refuse bad models."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from substruct.analysis.modes.dense import coupled_modes
from substruct.assembly.stack import Connection, PointRef, assemble
from substruct.case.loader import CaseError, load_case
from substruct.case.op4 import read_op4
from substruct.case.rigid_body import rigid_body_vectors
from substruct.io.op4 import write_op4
from substruct.models.beam import Material, Section
from substruct.models.craig_bampton import craig_bampton
from substruct.models.frame import FRAME_COMPONENTS, Beam, frame
from substruct.run.runner import run_case

SEC = Section(A=2.85e-3, Iy=1.94e-5, Iz=1.42e-6, J=7.0e-8)
MAT = Material(E=2.1e11, G=8.1e10, rho=7850.0)
NODES_A = {1: (0.0, 0.0, 0.0), 2: (1.5, 0.0, 0.0), 3: (3.0, 0.0, 0.0)}
NODES_B = {10: (3.0, 0.0, 0.0), 11: (3.0, 2.0, 0.5)}


def _part(name: str, nodes: dict, members: list, boundary: tuple, modes: int):
    sub = frame(name, nodes, [Beam(m, SEC, MAT, o, divisions=6) for m, o in members])
    b = [k for k, lab in enumerate(sub.dof_labels) if int(lab.split(":")[0]) in boundary]
    return sub, craig_bampton(sub, b, modes)


@pytest.fixture(scope="module")
def parts():
    a, ra = _part("a", NODES_A, [((1, 2), (0, 0, 1)), ((2, 3), (0, 0, 1))], (1, 3), 5)
    b, rb = _part("b", NODES_B, [((10, 11), (0, 0, 1))], (10,), 4)
    return a, ra, b, rb


def _dof_csv(red, path: Path) -> None:
    lines = ["grid,component"]
    for k, lab in enumerate(red.dof_labels):
        if lab.startswith("eta"):
            lines.append(f"{9000 + k},0")  # a modal coordinate (Nastran's SPOINT)
        else:
            g, c = lab.split(":")
            lines.append(f"{g},{FRAME_COMPONENTS.index(c) + 1}")
    path.write_text("\n".join(lines) + "\n")


CONNECT = "\n".join(f"  - [a@3:{c}, b@10:{k + 1}]" for k, c in enumerate(FRAME_COMPONENTS))


def _case(tmp: Path, extra_a: str = "", count: int = 14) -> Path:
    text = f"""name: two_superelements
substructures:
  - {{name: a, type: superelement, file: a.op4, M: MAA, K: kaa, dofs: {{file: a.csv}},
     grids: {{1: [0, 0, 0], 3: [3, 0, 0]}}{extra_a}}}
  - {{name: b, type: superelement, file: b.op4, M: MAA, K: KAA, dofs: {{file: b.csv}},
     grids: {{10: [3, 0, 0]}}}}
connections:
{CONNECT}
analysis:
  modes: {{count: {count}, method: generalized-inverse}}
"""
    (tmp / "case.yaml").write_text(text)
    return tmp / "case.yaml"


@pytest.fixture
def files(tmp_path: Path, parts):
    _, ra, _, rb = parts
    # a: binary, big-endian, 8-byte words, BIGMAT strings; b: text, dense columns
    write_op4(tmp_path / "a.op4", {"MAA": ra.M.toarray(), "KAA": ra.K.toarray()}, binary=True,
              order=">", int_bytes=8, storage="bigmat")
    write_op4(tmp_path / "b.op4", {"MAA": rb.M.toarray(), "KAA": rb.K.toarray()})
    _dof_csv(ra, tmp_path / "a.csv")
    _dof_csv(rb, tmp_path / "b.csv")
    return tmp_path


def test_op4_holds_the_reduction_bit_for_bit(files: Path, parts) -> None:
    _, ra, _, rb = parts
    for red, file in ((ra, "a.op4"), (rb, "b.op4")):
        got = read_op4(files / file)
        assert np.array_equal(got["MAA"].dense(), red.M.toarray())
        assert np.array_equal(got["KAA"].dense(), red.K.toarray())


def test_coupled_modes_equal_the_in_memory_coupling(files: Path, parts) -> None:
    """The case (superelements read from OP4) and the reductions coupled in memory: the same
    elastic system modes to 1e-10."""
    _, ra, _, rb = parts
    result = run_case(load_case(_case(files)))
    ties = [Connection(PointRef("a", f"3:{c}"), PointRef("b", f"10:{c}"))
            for c in FRAME_COMPONENTS]
    asm = assemble([ra, rb], ties)
    ref = coupled_modes(asm.M, None, asm.K, asm.A, method="generalized-inverse").omega
    got = result.modes.omega
    assert got.size == 14
    # the free pair's six rigid-body roots (set aside or kept near 0 alike), then the
    # elastic modes
    elastic = got > 1e-6 * got.max()
    assert (~elastic).sum() <= 6 and elastic.sum() >= 8
    assert np.all(got[~elastic] < 1e-6 * got.max())
    np.testing.assert_allclose(got[elastic], ref[ref > 1e-6 * ref.max()][:elastic.sum()],
                               rtol=1e-10)
    assert result.model.substructure_kinds == ["superelement", "superelement"]
    assert result.model.dof_labels[0] == "a.mode:1" and "b.10:rz" in result.model.dof_labels


def test_rigid_body_properties_equal_the_unreduced_frames(files: Path, parts) -> None:
    """Mass rho A L, the centre of gravity at the members' middles, and D^T M D of the
    Craig-Bampton model equal to that of the unreduced frame (its rigid-body motion lies in
    the span of the constraint modes)."""
    a, _, b, _ = parts
    case = load_case(_case(files))
    for spec, sub, length, middle in (
            (case.substructures[0], a, 3.0, [1.5, 0, 0]),
            (case.substructures[1], b, float(np.linalg.norm([0, 2, 0.5])), [3, 1, 0.25])):
        props = spec.rigid_body()
        assert props["mass"] == pytest.approx(MAT.rho * SEC.A * length, rel=1e-12)
        np.testing.assert_allclose(props["masses_xyz"], props["mass"], rtol=1e-12)
        np.testing.assert_allclose(props["cg"], middle, atol=1e-12 * length)
        dofs = [(int(lab.split(":")[0]), FRAME_COMPONENTS.index(lab.split(":")[1]) + 1)
                for lab in sub.dof_labels]
        nodes = {g: sub.position(f"{g}:ux") for g, _ in dofs}
        D = rigid_body_vectors(dofs, nodes, (0, 0, 0))
        full = D.T @ sub.M.toarray() @ D
        np.testing.assert_allclose(props["M_rb"], full, rtol=1e-9, atol=1e-9 * abs(full).max())
        assert props["frequency_ratio"] < 1e-5


def test_summary_prints_and_result_keeps_the_rigid_body_properties(files: Path) -> None:
    import io
    import json

    from substruct.cli.summary import print_summary

    result = run_case(load_case(_case(files, count=8)))
    props = json.loads(result.attrs["rigid_body:a"])
    assert props["mass"] == pytest.approx(MAT.rho * SEC.A * 3.0, rel=1e-12)
    out = io.StringIO()
    print_summary(result, out)
    assert f"superelement a: rigid-body mass {MAT.rho * SEC.A * 3.0:.6g}, centre of gravity " \
           f"[1.5, " in out.getvalue()


def test_grounded_model_refused_unless_declared_supported(files: Path, parts) -> None:
    """A spring to ground at grid 1 (k/m giving a rigid-body frequency of about 2 % of the
    first elastic one): refused as not free; accepted with free: false."""
    _, ra, _, rb = parts
    K = ra.K.toarray()
    k = list(ra.dof_labels).index("1:uy")
    K[k, k] += 1e5
    write_op4(files / "a.op4", {"MAA": ra.M.toarray(), "KAA": K}, binary=True)
    with pytest.raises(CaseError, match=r"substructures\.a\.K: matrix 'kaa' holds the "
                       r"rigid-body motion of the boundary grids: its rigid-body frequencies "
                       r"reach .* of the first elastic frequency"):
        load_case(_case(files))
    case = load_case(_case(files, extra_a=", free: false"))
    assert case.substructures[0].rigid_body()["free"] is False


@pytest.mark.parametrize("extra,message", [
    (", K4: KAA", r"substructures\.a\.W4: K4 \(structural damping\) and W4"),
    (", rigid_tolerance: 2", r"rigid_tolerance"),
])
def test_bad_keys(files: Path, extra: str, message: str) -> None:
    with pytest.raises(CaseError, match=message):
        load_case(_case(files, extra_a=extra))


def test_dof_map_problems(files: Path, parts) -> None:
    _, ra, _, _ = parts
    lines = (files / "a.csv").read_text().splitlines()
    (files / "a.csv").write_text("\n".join(lines[:-1]) + "\n")
    with pytest.raises(CaseError, match=r"substructures\.a\.dofs: the DOF map has 16 rows for "
                       r"the 17 coordinates"):
        load_case(_case(files))
    (files / "a.csv").write_text("\n".join(lines[:-1] + [lines[-2]]) + "\n")
    with pytest.raises(CaseError, match=r"grid 3 component 5 is mapped twice"):
        load_case(_case(files))


def test_inline_map_npz_matrices_k4_and_points(tmp_path: Path, parts) -> None:
    """The same model from an NPZ with an inline DOF map; K4 enters as K4 / W4; points by
    component name, digit and mode number."""
    _, ra, _, _ = parts
    M, K = ra.M.toarray(), ra.K.toarray()
    np.savez(tmp_path / "a.npz", M=M, K=K, G=0.02 * K)
    (tmp_path / "case.yaml").write_text("""name: one
substructures:
  - {name: a, type: superelement, file: a.npz, M: M, K: K, K4: G, W4: 100.0,
     dofs: [{modes: 5}, [1, "123456"], [3, "123456"]]}
  - {name: s, type: spring, stiffness: 1.0e+6, ground: true}
connections: [[a@3:z, s@i]]
analysis:
  frf: {omega: [10.0], inputs: [a@1:3], outputs: [a@mode:2, a@3:uz]}
""")
    case = load_case(tmp_path / "case.yaml")
    spec = case.substructures[0]
    np.testing.assert_array_equal(spec.matrix("C"), 0.02 * ((K + K.T) / 2) / 100.0)
    assert spec.dof_labels()[:2] == ["mode:1", "mode:2"] and spec.dof_labels()[5] == "1:ux"
    result = run_case(case)
    assert result.frf is not None and result.frf.H.shape[-2:] == (2, 1)
    (tmp_path / "case.yaml").write_text((tmp_path / "case.yaml").read_text()
                                        .replace("a@mode:2", "a@mode:9"))
    with pytest.raises(CaseError, match=r"superelement 'a' has no coordinate 'mode:9'"):
        run_case(load_case(tmp_path / "case.yaml"))


@pytest.mark.parametrize("table, message", [
    # a complex part was dropped and truth values read as ids 1 and 0
    (np.array([[1, 1], [2, 1]]) + 1j, r"dofs\.key: a DOF map is n x 2 integers \(grid, "
     r"component\), got complex128 entries"),
    (np.array([[True, True], [True, False]]), r"got bool entries"),
    # a value beyond int64 was shown as -9223372036854775808, the integer it was cast to
    (np.array([[1, 1], [2, 1e300]]), r"dofs\.key: row 2: component 1e\+300 is not 0-6"),
    (np.array([[1, 1], [1e12, 1]]), r"dofs\.key: row 2: grid 1e\+12 is not 1 to 999999999"),
])
def test_dof_map_member_of_numbers_that_are_not_ids(tmp_path: Path, table, message) -> None:
    np.savez(tmp_path / "a.npz", K=np.array([[2.0, -1.0], [-1.0, 2.0]]), M=np.eye(2),
             DOFS=table)
    (tmp_path / "case.yaml").write_text("""name: one
substructures:
  - {name: a, type: superelement, file: a.npz, M: M, K: K, dofs: {key: DOFS}, free: false}
analysis:
  modes: {count: 2}
""")
    with pytest.raises(CaseError, match=message):
        load_case(tmp_path / "case.yaml")
    np.savez(tmp_path / "a.npz", K=np.array([[2.0, -1.0], [-1.0, 2.0]]), M=np.eye(2),
             DOFS=np.array([[1, 1], [2, 1]]))
    assert load_case(tmp_path / "case.yaml").substructures[0].dof_labels() == ["1:ux", "2:ux"]
