"""A result file with a NaN or an infinite value is a corrupt file: every command that reads
results (``info``, ``export`` in each format, ``compare``) refuses it in one line naming the
file and the dataset (exit 2), before it prints a number or writes a file.

Each case starts from the good result of ``tests/test_export.py`` (with a ``/frf`` block) and
puts one value that is not finite into one dataset or attribute with h5py.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

from cli_helpers import run
from substruct.io import hdf5 as results
from test_export import make_result


def _value(path: str, index: tuple, value: complex):
    def mutate(f: h5py.File) -> None:
        data = f[path][()]
        data[index] = value
        f[path][...] = data
    return mutate


def _attr(path: str, key: str, value: float):
    def mutate(f: h5py.File) -> None:
        f[path].attrs[key] = value
    return mutate


NAN, INF = float("nan"), float("inf")
CASES = {  # name: (mutation, the dataset or attribute named in the message)
    "modes_omega_nan": (_value("modes/omega", (1,), NAN), "/modes/omega holds values that "
                        "are not finite: nan at index 1 (1 of 3)"),
    "modes_omega_inf": (_value("modes/omega", (0,), INF), "/modes/omega holds values that "
                        "are not finite: inf at index 0"),
    "modes_shapes_inf": (_value("modes/shapes", (4, 2), complex(0.0, -INF)),
                         "/modes/shapes holds values that are not finite"),
    "modes_eigenvalues_nan": (_value("modes/eigenvalues", (2,), complex(NAN, 1.0)),
                              "/modes/eigenvalues holds values that are not finite"),
    "modes_damping_nan": (_value("modes/damping_ratio", (0,), NAN),
                          "/modes/damping_ratio holds values that are not finite"),
    "modes_residual_inf": (_value("modes/constraint_residual", (0,), INF),
                           "/modes/constraint_residual holds values that are not finite"),
    "modes_tolerance_nan": (_attr("modes", "tolerance", NAN),
                            "/modes attribute tolerance is not finite, got nan"),
    "modes_agreement_inf": (_attr("modes", "agreement_kkt", INF),
                            "/modes attribute agreement_kkt is not finite, got inf"),
    "variant_omega_nan": (_value("variants/half/omega", (0,), NAN),
                          "/variants/half/omega holds values that are not finite"),
    "frf_omega_nan": (_value("frf/omega", (2,), NAN),
                      "/frf/omega holds values that are not finite: nan at index 2"),
    "frf_H_inf": (_value("frf/H", (1, 0, 0), complex(INF, 0.0)),
                  "/frf/H holds values that are not finite"),
    "frf_residual_nan": (_attr("frf", "constraint_residual", NAN),
                         "/frf attribute constraint_residual is not finite"),
    "interp_nan": (_value("model/drawings/0/interp/data", (0,), NAN),
                   "/model/drawings/0/interp/data holds values that are not finite"),
}


def _good(tmp_path: Path) -> Path:
    path = results.save(make_result(), tmp_path / "good.h5")
    with h5py.File(path, "a") as f:
        g = f.create_group("frf")
        g.attrs.update(method="kkt", constraint_residual=0.0)
        g["omega"] = np.arange(1.0, 4.0)
        g["H"] = np.full((3, 1, 1), 1e-3 + 2e-4j)
        g["inputs"] = np.array(["q1"], dtype=object).astype(h5py.string_dtype())
        g["outputs"] = np.array(["q1"], dtype=object).astype(h5py.string_dtype())
        f["modes"].attrs["agreement_kkt"] = 1e-15
    return path


def _hostile(tmp_path: Path, name: str) -> tuple[Path, Path]:
    good = _good(tmp_path)
    bad = tmp_path / f"{name}.h5"
    shutil.copy(good, bad)
    with h5py.File(bad, "a") as f:
        CASES[name][0](f)
    return good, bad


def test_the_starting_result_is_read_by_every_command(tmp_path, capsys):
    good = _good(tmp_path)
    other = shutil.copy(good, tmp_path / "other.h5")
    for args in (["info", good], ["export", good, "--format", "uff", "--out", tmp_path / "u"],
                 ["export", good, "--format", "vtu", "--out", tmp_path / "v"],
                 ["compare", good, other, "--variant-b", "half"]):
        code, out, err = run(capsys, *args)
        assert code == 0, (args, err)


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_command_refuses_a_value_that_is_not_finite(name, tmp_path, capsys):
    good, bad = _hostile(tmp_path, name)
    writes = [tmp_path / "vtu", tmp_path / "uff", tmp_path / "mac.png"]
    for args in (["info", bad], ["info", bad, "--json"],
                 ["export", bad, "--format", "vtu", "--out", writes[0]],
                 ["export", bad, "--format", "uff", "--out", writes[1]],
                 ["compare", good, bad, "--image", writes[2]],
                 ["compare", bad, good, "--json"]):
        code, out, err = run(capsys, *args)
        assert code == 2 and out == "", (args, err)
        assert err.startswith(f"substruct: error: {bad}: not a substruct result: "), err
        assert err.count("\n") == 1 and "Traceback" not in err, err
        assert CASES[name][1] in err, err
    assert not any(p.exists() for p in writes)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([good.name, bad.name])
