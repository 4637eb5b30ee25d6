"""The shipped coupled loads example, ``cases/two_superelements.yaml``: a spacecraft on an
adapter, both Craig-Bampton superelements in OP4 with recovery matrices, under a lateral base
acceleration pulse at the launcher interface.  Run through the command line, its recovered
peaks are checked against the same transient of the unreduced FE assembly (the beam models the
superelements were reduced from, by ``cases/superelements/make_superelements.py``), and its
interface force (IFLTM) against the connection's Lagrange multipliers, an independent
formulation of the same force."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from substruct import cli
from substruct.case.loader import load_case
from substruct.io.hdf5 import load
from substruct.models.frame import FRAME_COMPONENTS
from substruct.run.runner import run_case

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "two_superelements.yaml"


def _maker():
    spec = importlib.util.spec_from_file_location(
        "make_superelements", ROOT / "cases" / "superelements" / "make_superelements.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _full_case(tmp: Path, adapter_file: str) -> Path:
    """The shipped case with the unreduced beam models as matrix superelements (their
    Rayleigh damping as C) and every spacecraft coordinate the recoveries need as an
    output."""
    mk = _maker()
    subs = {"adapter": mk.adapter_model(mk.TUBE_STIFF if "stiff" in adapter_file
                                        else mk.TUBE),
            "spacecraft": mk.spacecraft_model()}
    for name, sub in subs.items():
        np.savez(tmp / f"{name}_full.npz", M=sub.M.toarray(), K=sub.K.toarray(),
                 C=mk.damping(sub), DOFS=mk.dof_rows(sub.dof_labels))
    case = yaml.safe_load(CASE.read_text())
    for sub in case["substructures"]:
        sub.update(file=f"{sub['name']}_full.npz", M="M", K="K", C="C", dofs={"key": "DOFS"})
        sub.pop("recovery", None)
        sub.pop("grids")  # every node of the full model is a "boundary" grid
    del case["analysis"]["frf"]
    case["analysis"]["transient"]["outputs"] = [
        f"spacecraft@{g}:{c}" for g in (101, 102, 100, 103) for c in FRAME_COMPONENTS]
    text = yaml.safe_dump(case)
    path = tmp / "full.yaml"
    path.write_text(text)
    return path


def _reference(full, K_root: np.ndarray) -> dict[str, np.ndarray]:
    """The recovered quantities from the unreduced model's response: the accelerations at
    101, 102; the mast root element's end forces K_e[0:6] u_e; the interface force on the
    spacecraft, -lambda of the connection rows (Q^c = A^T lambda, A = [I, -I])."""
    tr = full.transient
    idx = {p: k for k, p in enumerate(tr.outputs)}
    col = [idx[f"spacecraft@{g}:{c}"] for g in (101, 102) for c in FRAME_COMPONENTS[:3]]
    elem = [idx[f"spacecraft@{g}:{c}"] for g in (100, 103) for c in FRAME_COMPONENTS]
    links = [tr.constraint_labels.index(f"adapter@2:{c} = spacecraft@100:{c}")
             for c in FRAME_COMPONENTS]
    return {"spacecraft.atm": tr.acceleration[:, col],
            "spacecraft.mast_root": tr.displacement[:, elem] @ K_root[:6].T,
            "spacecraft.interface": -tr.constraint_forces[:, links]}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The shipped case through the command line (the adapter and the stiffer adapter), and
    the unreduced assembly of each in process."""
    tmp = tmp_path_factory.mktemp("cla")
    out = {}
    for key, adapter in (("soft", "adapter.op4"), ("stiff", "adapter_stiff.op4")):
        assert cli.main(["run", str(CASE), "--out", str(tmp / key), "--force", "--quiet",
                         "--set", f"substructures.adapter.file=superelements/{adapter}"]) == 0
        red = load(tmp / key / "two_superelements.h5")
        work = tmp / f"full_{key}"
        work.mkdir()
        full = run_case(load_case(_full_case(work, adapter)))
        out[key] = (red, full)
    return tmp, out


#: The reduction's error (adapter 6, spacecraft 12 fixed-interface modes) relative to each
#: recovery's largest value, about three times the largest measured on either adapter (peaks;
#: whole histories): accelerations 3.1e-5; 7.5e-5, interface force 1.6e-5; 1.6e-5, mast root
#: element forces 1.3e-3; 4.7e-3 (a mode displacement LTM converges slower than the
#: accelerations and the boundary force: the interior strain of the truncated modes is lost).
TOLERANCE = {"spacecraft.atm": 3e-4, "spacecraft.interface": 1e-4,
             "spacecraft.mast_root": 1.5e-2}


def test_recovered_peaks_match_the_unreduced_assembly(runs) -> None:
    """Each recovered row's largest and smallest value and their instants against the same
    quantity of the unreduced beam models under the same base pulse."""
    mk = _maker()
    K_root = mk.mast_root_stiffness()
    for key, (red, full) in runs[1].items():
        ref = _reference(full, K_root)
        assert [r.title for r in red.recovery] == list(ref)
        for rec in red.recovery:
            y = ref[rec.title]
            assert rec.history.shape == y.shape
            p = rec.peaks()
            scale = np.abs(y).max()
            for got, want in ((p.max, y.max(axis=0)), (p.min, y.min(axis=0))):
                err = np.abs(got - want).max() / scale
                assert err < TOLERANCE[rec.title], (key, rec.title, err)
            # the whole history, not only its extremes
            err = np.abs(rec.history - y).max() / scale
            assert err < TOLERANCE[rec.title], (key, rec.title, err)
            # the instants of the large peaks within one step
            dt = float(full.transient.t[1] - full.transient.t[0])
            for got_t, want_k, value in ((p.t_max, np.argmax(y, axis=0), p.max),
                                         (p.t_min, np.argmin(y, axis=0), p.min)):
                big = np.abs(value) > 0.3 * scale
                assert np.all(np.abs(got_t - full.transient.t[want_k])[big] <= dt * 1.001)


def test_interface_force_is_the_connection_force(runs) -> None:
    """In the reduced run itself, the IFLTM rows [M_b C_b K_b] [a v x] equal the Lagrange
    multipliers of the connection (the same force, solved for by the constraint), to the
    rounding of the integration."""
    red = runs[1]["soft"][0]
    tr = red.transient
    links = [tr.constraint_labels.index(f"adapter@2:{c} = spacecraft@100:{c}")
             for c in FRAME_COMPONENTS]
    rec = next(r for r in red.recovery if r.title == "spacecraft.interface")
    lam = -tr.constraint_forces[:, links]
    assert np.abs(rec.history - lam).max() < 1e-8 * np.abs(lam).max()


def test_compare_gives_the_peaks_table(runs, capsys) -> None:
    """``substruct compare`` of the two adapters: every recovered row of both runs, with the
    change of its peak magnitude."""
    tmp, got = runs
    a, b = tmp / "soft" / "two_superelements.h5", tmp / "stiff" / "two_superelements.h5"
    assert cli.main(["compare", str(a), str(b), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["peaks"]
    assert len(rows) == 18
    recs = {r.title: r for r in got["soft"][0].recovery}, \
        {r.title: r for r in got["stiff"][0].recovery}
    for row in rows:
        ra, rb = (r[row["recovery"]] for r in recs)
        k = ra.labels.index(row["row"])
        ea, eb = np.abs(ra.peaks().extreme()[k]), np.abs(rb.peaks().extreme()[k])
        assert row["change"] == pytest.approx((eb - ea) / ea, rel=1e-12)
        assert row["max_a"] == ra.peaks().max[k] and row["min_b"] == rb.peaks().min[k]
    assert cli.main(["compare", str(a), str(b)]) == 0
    assert "recovered peaks (18 quantities in both; largest change first):" in \
        capsys.readouterr().out
