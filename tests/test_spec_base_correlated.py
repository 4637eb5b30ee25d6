"""Several correlated base inputs (``analysis.random.bases`` with ``cross``): two supports of a
two-mass model shaken by tables whose accelerations have a coherence and a phase, run
through the command line and held to a direct computation written here: per frequency the
KKT system of the constrained model with each table's row moved by a unit acceleration gives
the transmissibility columns ``T`` (``q x 2``), and ``S_y = T S_f T^H`` with ``S_f`` built
from the two tables and the pair's coherence and phase by hand."""

import h5py
import numpy as np
import yaml

from base_drive_reference import dense_transmissibility
from cli_helpers import run
from substruct.case.loader import load_case

CASE = {
    "name": "two_tables",
    "units": "N, m, kg, s",
    "substructures": [
        {"name": "a", "type": "free-free", "mass": 1.0, "stiffness": 1.0e4, "damping": 6.0},
        {"name": "b", "type": "free-free", "mass": 2.0, "stiffness": 3.0e4, "damping": 9.0},
        {"name": "c", "type": "free-free", "mass": 0.5, "stiffness": 5.0e3, "damping": 2.0},
    ],
    "connections": [["a@mass", "c@boundary"], ["c@mass", "b@mass"]],
    "constraints": [{"name": "ta", "terms": {"a@boundary": 1}},
                    {"name": "tb", "terms": {"b@boundary": 2}}],
    "analysis": {"random": {
        "frequencies": {"start": 2, "stop": 60, "num": 300, "spacing": "log"},
        "bases": [{"name": "left", "at": ["a@boundary"], "psd": [[2, 1.0], [60, 1.0]]},
                  {"name": "right", "at": ["b@boundary"], "psd": [[2, 2.0], [60, 0.5]]}],
        "cross": [{"between": ["left", "right"], "coherence": 0.6, "phase": 30}],
        "outputs": ["a@mass", "b@mass", "c@mass"],
        "check": ["null-space"]}},
    "output": {"pictures": False},
}


def direct(case, f):
    """``T`` ``(n_f, outputs, bases)`` of ``analysis.random`` by a dense KKT solve per
    frequency (:func:`base_drive_reference.dense_transmissibility`)."""
    return dense_transmissibility(case, case.analysis.random, f)


def test_correlated_tables_against_the_direct_computation(capsys, tmp_path):
    path = tmp_path / "two_tables.yaml"
    path.write_text(yaml.safe_dump(CASE))
    code, out, err = run(capsys, "run", path, "--out", tmp_path / "out")
    assert code == 0, err
    assert "Miles' check" not in out  # two inputs: no single transmissibility
    with h5py.File(tmp_path / "out" / "two_tables.h5") as h5:
        f, psd, rms = h5["random/f"][()], h5["random/psd"][()], h5["random/rms"][()]
        csd = h5["random/input_csd"][()]
        assert [s.decode() for s in h5["random/inputs"][()]] == ["left", "right"]
    s1 = np.ones_like(f)
    s2 = np.exp(np.interp(np.log(f), np.log([2, 60]), np.log([2.0, 0.5])))
    s12 = np.sqrt(0.6 * s1 * s2) * np.exp(1j * np.pi / 6)
    S = np.empty((len(f), 2, 2), dtype=complex)
    S[:, 0, 0], S[:, 1, 1], S[:, 0, 1], S[:, 1, 0] = s1, s2, s12, np.conj(s12)
    np.testing.assert_allclose(csd, S, rtol=1e-12, atol=1e-14)
    T = direct(load_case(path), f)
    Sy = T @ S @ np.conj(T).transpose(0, 2, 1)
    # the run's formulations agree to its tolerance, 1e-6 of max |H|: the response matrix
    # (quadratic in H) to a few times that of its largest term
    scale = np.abs(Sy).max()
    assert np.abs(psd - Sy).max() <= 4e-6 * scale, np.abs(psd - Sy).max() / scale
    auto = np.real(np.einsum("kii->ki", Sy))
    np.testing.assert_allclose(rms, np.sqrt(np.trapezoid(auto, f, axis=0)), rtol=4e-6)
    # the cross terms matter: the uncorrelated sum differs by far more than the tolerance
    uncorrelated = np.sqrt(np.trapezoid(np.abs(T[:, :, 0]) ** 2 * s1[:, None]
                                        + np.abs(T[:, :, 1]) ** 2 * s2[:, None], f, axis=0))
    assert np.abs(rms / uncorrelated - 1).max() > 0.05, rms / uncorrelated
