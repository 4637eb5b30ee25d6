"""Write the data of ``cases/vpt_coupling.yaml`` and of the ``tests/bad_cases/vp_*.yaml`` cases.

``cases/vpt_coupling/``: the two steel frames of :mod:`testlab_models` (``A`` free, ``B``
clamped), each "measured" by three triaxial sensors and nine impacts on a 50 mm adapter at
their joint: ``<part>_channels.csv`` (the channel table; A also has a sensor ``A4x`` at node 4, B an impact ``B14x``
at node 14, which pass through) and ``<part>.npz`` (``H`` on the
channel names as labels, sensors x impacts filled, the rest zero; ``omega``: 40 frequencies,
5 to 600 Hz).  ``tests/bad_cases/data/vp_*``: a small part (three frequencies) and channel
tables with a defect.  Usage, from the repository root::

    PYTHONPATH=$PWD python tests/make_vpt_case.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

from testlab_models import (OMEGA, adapter_rows, measure, node_rows, part_a,  # noqa: E402
                            part_b)

from substruct.case.channels import parse_channels, write_channels  # noqa: E402


def square(labels: list[str], sensors: list[str], impacts: list[str], Y: np.ndarray
           ) -> np.ndarray:
    """``Y`` (sensors x impacts) placed in a square matrix on ``labels``."""
    H = np.zeros((Y.shape[0], len(labels), len(labels)), dtype=complex)
    i = [labels.index(s) for s in sensors]
    j = [labels.index(h) for h in impacts]
    H[:, np.asarray(i)[:, None], np.asarray(j)[None, :]] = Y
    return H


def write_part(name: str, sub, seed: int, out: Path, extra: list[dict]) -> None:
    m = measure(sub, adapter_rows("", (0.0, 0.0, 0.0), seed) + extra)
    write_channels(m.table, out / f"{name.lower()}_channels.csv")
    labels = [c.name for c in m.table.channels]
    np.savez(out / f"{name.lower()}.npz", H=square(labels, m.sensors, m.impacts, m.Y),
             labels=np.array(labels), omega=OMEGA)


def write_bad(out: Path) -> None:
    """A table of three triaxial sensors and six impacts, the same with the sensors on one
    line through the virtual point, and receptances on their names."""
    rng = np.random.default_rng(7)
    rows, line = [], []
    spots = [(0.02, 0.01, -0.01), (-0.015, 0.02, 0.01), (0.005, -0.02, 0.02)]
    for s, spot in enumerate(spots):
        axes = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        for a in range(3):
            d = axes[:, a]
            common = dict(name=f"S{s + 1}{'xyz'[a]}", node=str(s + 1), dx=d[0], dy=d[1],
                          dz=d[2], kind="sensor")
            rows.append(dict(common, x=spot[0], y=spot[1], z=spot[2]))
            line.append(dict(common, x=0.01 * (s + 1), y=0.0, z=0.0))
    for h in range(6):
        p, d = rng.uniform(-0.025, 0.025, 3), rng.normal(size=3)
        hit = dict(name=f"H{h + 1}", node=str(10 + h), x=p[0], y=p[1], z=p[2], dx=d[0],
                   dy=d[1], dz=d[2], kind="impact")
        rows.append(hit)
        line.append(hit)
    write_channels(parse_channels(rows, "vp"), out / "vp_channels.csv")
    write_channels(parse_channels(line, "vp"), out / "vp_collinear.csv")
    labels = [r["name"] for r in rows]
    X = rng.normal(size=(3, len(labels), len(labels))) * 1e-6 + \
        1j * rng.normal(size=(3, len(labels), len(labels))) * 1e-7
    np.savez(out / "vp_part.npz", H=X + np.swapaxes(X, 1, 2), labels=np.array(labels),
             omega=np.array([10.0, 20.0, 30.0]))


if __name__ == "__main__":
    out = ROOT / "cases" / "vpt_coupling"
    out.mkdir(exist_ok=True)
    A, B = part_a(), part_b()
    # a sensor away from the joint on A, an impact away from it on B: they pass through
    write_part("A", A, 11, out, [node_rows("A4x", A, 4, (1, 0, 0), "sensor")])
    write_part("B", B, 21, out, [node_rows("B14x", B, 14, (1, 0, 0), "impact")])
    write_bad(ROOT / "tests" / "bad_cases" / "data")
    write_bad_testlab(ROOT / "tests" / "bad_cases" / "data")
    tpa = ROOT / "cases" / "vpt_coupling_tpa"
    tpa.mkdir(exist_ok=True)
    write_tpa(tpa)


#: the source of cases/vpt_coupling_tpa.yaml: forces at A's nodes 3 (z) and 4 (x)
TPA_SOURCE = [("3:uz", 1.0), ("4:ux", 0.4 - 0.3j)]
#: its indicators on B (translations of three nodes) and validation targets (B's node ids)
TPA_INDICATORS = [(f"I{3 * k + a + 1}", node, axis) for k, node in enumerate((15, 12, 14))
                  for a, axis in enumerate(((1, 0, 0), (0, 1, 0), (0, 0, 1)))]
TPA_TARGETS = [("T1", 20, (0, 0, 1)), ("T2", 17, (0, 1, 0)), ("T3", 16, (0, 0, 1))]


def node_at(sub, xyz) -> int:
    """The node of ``sub`` at ``xyz``."""
    for label in sub.dof_labels:
        if label.endswith(":ux") and np.allclose(sub.position(label), xyz, atol=1e-12):
            return int(label.split(":")[0])
    raise KeyError(xyz)


def write_tpa(out: Path) -> None:
    """``cases/vpt_coupling_tpa/``: B with the adapter and the indicator and target sensors
    (``b.npz``, ``b_channels.csv``), and the operating responses of the assembly with the
    source running (``operating.npz``: at the indicators, the targets and the joint)."""
    import scipy.sparse as sp

    from testlab_models import assembly, channel_matrix, node_dofs, receptance

    B, AB = part_b(), assembly()
    extra = [node_rows(n, B, node, d, "sensor") for n, node, d in TPA_INDICATORS + TPA_TARGETS]
    write_part("B", B, 21, out, extra)
    table = parse_channels(extra, "B")
    names = [c.name for c in table.channels]
    on_ab = {n: node_at(AB, B.position(f"{node}:ux")) for n, node, _ in
             TPA_INDICATORS + TPA_TARGETS}
    S = sp.vstack([channel_matrix(AB, table, names, on_ab), node_dofs(AB, 1)])
    src = sp.vstack([AB.locate(d) for d, _ in TPA_SOURCE])
    u = receptance(AB, sp.csr_array(S), sp.csr_array(src)) @ np.array([a for _, a in TPA_SOURCE])
    labels = [f"B@ch:{n}" for n in names] + [f"A@vp:J:{c}" for c in
                                              ("ux", "uy", "uz", "rx", "ry", "rz")]
    np.savez(out / "operating.npz", omega=OMEGA, labels=np.array(labels), u=u)


def write_bad_testlab(out: Path) -> None:
    """``tests/bad_cases/data/tpa_*.npz``, ``semm_*.npz``: operating responses (one of them
    not finite, one out of range) and a measured receptance on a three-mass model's points."""
    w = np.array([1.0, 2.0, 3.0])
    labels = np.array(["P@q1", "P@q2", "P@q3"])
    u = np.arange(9.0).reshape(3, 3) + 1j
    np.savez(out / "tpa_responses.npz", omega=w, labels=labels, u=u)
    u = u.copy()
    u[1, 2] = np.nan
    np.savez(out / "tpa_responses_nan.npz", omega=w, labels=labels, u=u)
    u = np.arange(9.0).reshape(3, 3) + 1j
    u[2, 0] = 3e300
    np.savez(out / "tpa_responses_huge.npz", omega=w, labels=labels, u=u)
    np.savez(out / "semm_measured.npz", omega=w, outputs=labels[:2], inputs=labels[:1],
             H=np.ones((3, 2, 1), dtype=complex))
