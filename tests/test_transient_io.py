"""The ``/transient/`` group of a results file read back: the same object to the last bit,
listed by ``info``, and hostile groups (mismatched lengths, NaN, 3 GB declared shapes, times
that go back) refused in one line, exit 2, like the other groups of the layout."""

import dataclasses
import re
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

from cli_helpers import run
from substruct.analysis.transient import LoadHistory, TransientOptions, TransientOutputs, transient
from substruct.io import hdf5 as results
from test_export import make_result


def _tied_transient(n_dof):
    """A run of the tied two-mass model with a massless absorber coordinate (forces, energy,
    snapshots every 5 steps), padded with zero coordinates to the result's ``n_dof``."""
    M = sp.diags_array([1.0, 2.0, 0.0, 0.5] + [1.0] * (n_dof - 4)).tocsr()
    K = sp.block_diag([sp.csr_array(np.array([[900.0, -100, 0, 0], [-100, 400, 0, 0],
                                              [0, 0, 300, -300], [0, 0, -300, 300]])),
                       sp.identity(n_dof - 4) * 50.0]).tocsr()
    A = sp.csr_array((np.array([1.0, -1.0, 1.0, -1.0]), ([0, 0, 1, 1], [0, 1, 1, 2])),
                     shape=(2, n_dof))
    B = np.zeros((n_dof, 1))
    B[3] = 1.0
    n = 40
    t = 1e-3 * np.arange(n + 1)
    O = sp.csr_array(np.eye(n_dof)[[0, 3]])
    return transient(M, 0.01 * K, K, A, None, LoadHistory(B, np.sin(40 * t)[:, None], 1e-3, n),
                     TransientOutputs(O, ["m1", "absorber"]),
                     constraint_labels=["tie 1-2", "tie 2-3"],
                     options=TransientOptions(checks=["null-space"],
                                              integrator="generalized-alpha", rho_inf=0.8,
                                              field_every=5))


def _with_transient():
    r = make_result()
    r.transient = _tied_transient(len(r.model.dof_labels))
    return r


def _same(a, b):
    assert type(a) is type(b)
    if isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape
        assert a.tobytes() == b.tobytes()  # to the last bit (NaN-free, so no sign games)
    else:
        assert a == b, (a, b)


def test_round_trip_is_exact_to_the_last_bit(tmp_path):
    r = _with_transient()
    tr = r.transient
    assert tr.snapshots.shape == (9, 21) and tr.constraint_forces.shape == (41, 2)
    assert tr.agreement["null-space"] < 1e-10
    back = results.load(results.save(r, tmp_path / "r.h5")).transient
    assert back is not None
    for f in dataclasses.fields(tr):
        _same(getattr(tr, f.name), getattr(back, f.name))
    assert back.steps == 40


def test_snapshots_written_in_blocks_read_back_identical(tmp_path):
    """The snapshots of the field written two instants (a chunk) at a time: the same bits."""
    r = _with_transient()
    path = results.save(r, tmp_path / "r.h5", block_bytes=2 * 21 * 8, chunk_bytes=2 * 21 * 8)
    with h5py.File(path, "r") as f:
        assert f["transient/snapshots"].chunks == (2, 21)
    _same(results.load(path).transient.snapshots, r.transient.snapshots)


def test_round_trip_without_forces_or_snapshots(tmp_path):
    r = make_result()
    full = _tied_transient(21)
    r.transient = dataclasses.replace(full, constraint_forces=np.zeros((0, 2)),
                                      snapshot_t=np.zeros(0), snapshots=np.zeros((0, 0)),
                                      agreement={})
    back = results.load(results.save(r, tmp_path / "r.h5")).transient
    for f in dataclasses.fields(full):
        _same(getattr(r.transient, f.name), getattr(back, f.name))


def _set(name, value):
    def mutate(g):
        del g[name]
        g[name] = value
    return mutate


def _huge(name, shape):
    def mutate(g):
        del g[name]
        g.create_dataset(name, shape=shape, dtype=float, chunks=True)  # nothing stored
    return mutate


def _attr(key, value):
    def mutate(g):
        if value is None:
            del g.attrs[key]
        else:
            g.attrs[key] = value
    return mutate


HOSTILE = {
    "displacement_short": (_set("displacement", np.zeros((40, 2))),
                           "/transient/displacement has shape (40, 2), expected (41, 2)"),
    "velocity_columns": (_set("velocity", np.zeros((41, 3))), "/transient/velocity has shape"),
    "energy_1d": (_set("energy", np.zeros(41)), "/transient/energy has shape (41,)"),
    "residual_long": (_set("constraint_residual", np.zeros(42)),
                      "/transient/constraint_residual has shape (42,)"),
    "forces_rows": (_set("constraint_forces", np.zeros((7, 2))),
                    "constraint_forces has 7 rows for 41 instants"),
    "forces_columns": (_set("constraint_forces", np.zeros((41, 5))),
                       "/transient/constraint_forces has shape (41, 5)"),
    "t_nan": (_set("t", np.r_[0.0, np.nan, 1e-3 * np.arange(2, 41)]),
              "/transient/t holds values that are not finite"),
    "t_backwards": (_set("t", 1e-3 * np.arange(41)[::-1]), "/transient/t is not strictly"),
    "displacement_nan": (_set("displacement", np.full((41, 2), np.nan)),
                         "/transient/displacement holds values that are not finite"),
    "acceleration_inf": (_set("acceleration", np.full((41, 2), np.inf)), "not finite"),
    "displacement_3GB": (_huge("displacement", (200_000_000, 2)),
                         "declares (200000000, 2) x float64 (3.2 GB), more than the 1 GB"),
    "t_3GB": (_huge("t", (400_000_000,)), "/transient/t declares (400000000,)"),
    "snapshots_columns": (_set("snapshots", np.zeros((9, 4))),
                          "/transient/snapshots has shape (9, 4), expected (9, 21)"),
    "outputs_not_strings": (_set("outputs", np.zeros(2)), "/transient/outputs holds float64"),
    "dt_missing": (_attr("dt", None), "/transient has no attribute 'dt'"),
    "dt_negative": (_attr("dt", -1e-3), "attribute dt is -0.001, not > 0"),
    "drift_nan": (_attr("drift", np.nan), "attribute drift is not finite"),
    "soft_link": (_set("t", h5py.SoftLink("/transient/t")), "/transient/t is a SoftLink"),
}

#: a moving ground's datasets of the wrong shape (written beside the group's own)
HOSTILE_BASE = {
    "base_motion_columns": ({"base_motion": np.zeros((41, 2)), "base_influence": np.zeros(2)},
                            "/transient/base_motion has shape (41, 2), expected (41, 3)"),
    "base_influence_length": ({"base_motion": np.zeros((41, 3)), "base_influence": np.zeros(3)},
                              "/transient/base_influence has shape (3,), expected (2,)"),
}


def _add(items):
    def mutate(g):
        for name, value in items.items():
            g[name] = value
    return mutate


HOSTILE.update({name: (_add(items), fragment)
                for name, (items, fragment) in HOSTILE_BASE.items()})


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_transient_group_is_refused_in_one_line(name, tmp_path, capsys):
    path = results.save(_with_transient(), tmp_path / "r.h5")
    mutate, fragment = HOSTILE[name]
    with h5py.File(path, "a") as f:
        mutate(f["transient"])
    for args in (["info", path], ["info", path, "--json"],
                 ["export", path, "--format", "vtu", "--out", tmp_path / "vtu"]):
        code, out, err = run(capsys, *args)
        assert code == 2 and out == "", (args, err)
        assert err.startswith(f"substruct: error: {path}: not a substruct result: "), err
        assert err.count("\n") == 1 and "Traceback" not in err
        assert fragment in err, err
    assert not (tmp_path / "vtu").exists()


def _documented_transient():
    """The dataset and attribute names of the ``/transient`` section of docs/results.md."""
    text = (Path(__file__).resolve().parents[1] / "docs" / "results.md").read_text()
    section = text.split("## `/transient`", 1)[1].split("\n## ", 1)[0]
    tables = [[re.match(r"\| `([^`]+)` \|", line).group(1) for line in block.splitlines()
               if re.match(r"\| `([^`]+)` \|", line)]
              for block in section.split("\n\n") if block.startswith("| dataset")
              or block.startswith("| attribute")]
    return set(tables[0]), set(tables[1])


def test_results_doc_lists_every_transient_dataset_and_attribute(tmp_path):
    """docs/results.md's /transient table against a written file (with a moving ground, so the
    optional datasets are there), both ways; the ground's datasets read back to the last bit."""
    r = _with_transient()
    tr = r.transient
    k, n_out = len(tr.t), len(tr.outputs)
    r.transient = dataclasses.replace(tr, base_motion=np.linspace(0, 1, 3 * k).reshape(k, 3),
                                      base_influence=np.arange(1.0, n_out + 1))
    path = results.save(r, tmp_path / "r.h5")
    datasets, attributes = _documented_transient()
    with h5py.File(path, "r") as f:
        g = f["transient"]
        assert set(g.keys()) == datasets
        written = {("agreement_<form>" if a.startswith("agreement_") else a) for a in g.attrs}
        assert written == attributes
        np.testing.assert_array_equal(g["relative_velocity"][()],
                                      tr.velocity - r.transient.base_motion[:, 1:2]
                                      * r.transient.base_influence[None, :])
    back = results.load(path).transient
    _same(back.base_motion, r.transient.base_motion)
    _same(back.base_influence, r.transient.base_influence)
