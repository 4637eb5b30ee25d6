"""output: {matrices: true} stores the assembly's M, K, C in the result file (issue 14), and
they are the model that was solved: its constrained eigenvalues, computed here independently
(dense null space of A and scipy's eigh), are the run's frequencies."""

from pathlib import Path

import h5py
import numpy as np
import scipy.linalg as la

from substruct import cli
from substruct.io.hdf5 import load

CASE = Path(__file__).resolve().parent.parent / "cases" / "tapered_rod_fe.yaml"


def test_matrices_stored_on_request_and_they_give_the_modes(tmp_path):
    args = ["run", str(CASE), "--out", str(tmp_path), "--quiet", "--force",
            "--set", "output.pictures=false", "--set", "substructures.rod.discretization.elements=16"]
    assert cli.main(args) == 0
    with h5py.File(tmp_path / "tapered_rod_fe.h5") as f:
        assert "M" not in f["model"] and "K" not in f["model"]   # not asked: not stored
    assert cli.main([*args, "--set", "output.matrices=true"]) == 0
    result = load(tmp_path / "tapered_rod_fe.h5")
    mats = result.model.matrices
    assert sorted(mats) == ["C", "K", "M"] and mats["K"].shape == (38, 38)
    assert mats["C"].nnz == 0                                     # the model is undamped
    T = la.null_space(result.model.A.toarray())
    lam = la.eigh(T.T @ mats["K"].toarray() @ T, T.T @ mats["M"].toarray() @ T,
                  eigvals_only=True)
    np.testing.assert_allclose(np.sqrt(lam[:6]), result.modes.omega, rtol=1e-9)
