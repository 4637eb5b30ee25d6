"""HDF5 results: exact round trip, atomic writes, clear errors for foreign files."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

import substruct
from substruct.io import hdf5 as results
from substruct.builder.drawing import Drawing
from substruct.analysis.results import Modes, Receptance
from substruct.run.result import ModelInfo, Result

CASE_YAML = "name: synthetic\n# ünïcode survives: ω, ζ\nsubstructures: {}\n"


def _modes(rng: np.random.Generator, n: int, k: int, n_spurious: int, method: str) -> Modes:
    lam = -0.01 * np.arange(1, k + 1) + 1j * np.arange(1, k + 1) * 10.0
    return Modes(
        method=method,
        eigenvalues=lam,
        omega=np.abs(lam),
        damping_ratio=-lam.real / np.abs(lam),
        shapes=rng.standard_normal((n, k)) + 1j * rng.standard_normal((n, k)),
        residual=rng.random(k) * 1e-14,
        spurious=np.zeros(n_spurious, complex) + 1e-9j * np.arange(n_spurious),
        spurious_reason=[f"zero root {i}: violates A u = 0 (|A u| = 0.{i})"
                         for i in range(n_spurious)],
        agreement={"null-space": 1.5e-13, "kkt": 2.25e-12},
        solver="dense (sparse asked, but 4 free coordinates are too few for 3 modes and a "
               "Krylov basis)" if method == "kkt" else "sparse",
        tolerance=2.5e-5,
    )


def make_result(*, modes=True, frf=True, variants=True, n_constraints=2, n_spurious=4,
                drawings=True, seed=0) -> Result:
    """A synthetic result: a 4-coordinate rod, a fixed-free and a free-free attachment."""
    rng = np.random.default_rng(seed)
    n = 7
    xs = np.linspace(0.0, 200.0, 11)
    rod_rows = np.sin(np.outer(xs, 2 * np.arange(1, 5) - 1) * np.pi / 400.0)
    coo = sp.coo_array(rod_rows)
    rod_interp = sp.csr_array((coo.data, (3 * coo.row, coo.col)), shape=(33, n))
    rod = Drawing(
        name="rod", kind="rod/assumed-modes",
        points=np.column_stack([xs, np.zeros(11), np.zeros(11)]),
        cells=[("line", np.column_stack([np.arange(10), np.arange(1, 11)]))],
        interp=rod_interp, glyphs={"x=50": 2, "x=200": 10},
    )
    ff = Drawing(
        name="a", kind="fixed-free", points=np.array([[50.0, 0, 0], [50.0, -20, 0]]),
        cells=[("line", np.array([[0, 1]]))],
        interp=sp.csr_array(([1.0], ([0], [4])), shape=(6, n)),
        glyphs={"mass": 0, "boundary": 0, "ground": 1},
    )
    tet = Drawing(
        name="block", kind="solid", points=rng.random((5, 3)),
        cells=[("tetra", np.array([[0, 1, 2, 3], [1, 2, 3, 4]])), ("vertex", np.array([[4]]))],
        interp=sp.csr_array(rng.random((15, n)) * (rng.random((15, n)) < 0.3)), glyphs={},
    )
    mask = rng.random((n_constraints, n)) < 0.5
    A = sp.csr_array(rng.standard_normal((n_constraints, n)) * mask)
    model = ModelInfo(
        dof_labels=["rod.a1", "rod.a2", "rod.a3", "rod.a4", "a.mass", "d.mass", "d.boundary"],
        substructure_names=["rod", "a", "d"],
        substructure_kinds=["rod/assumed-modes", "fixed-free", "free-free"],
        offsets=np.array([0, 4, 5, 7]),
        A=A, b=np.arange(n_constraints, dtype=float),
        R=sp.csr_array((n_constraints, n)) if n_constraints == 0 else
        sp.csr_array(([1.0], ([0], [3])), shape=(n_constraints, n)),
        constraint_labels=[f"constraint {i + 1}: rod@{i} = a@mass" for i in range(n_constraints)],
        drawings=[rod, ff, tet] if drawings else [],
    )
    return Result(
        case_name="synthetic",
        case_yaml=CASE_YAML,
        model=model,
        modes=_modes(rng, n, 3, n_spurious, "generalized-inverse") if modes else None,
        frf=Receptance(
            method="generalized-inverse", omega=np.linspace(1.0, 50.0, 5),
            H=rng.standard_normal((5, 2, 3)) + 1j * rng.standard_normal((5, 2, 3)),
            inputs=["rod@200", "a@mass", "d@mass"], outputs=["rod@50", "rod@200"],
            agreement={"kkt": 3e-15}, constraint_residual=1e-16, tolerance=1e-3,
        ) if frf else None,
        variants={"without constraint (52)": _modes(rng, n, 2, 0, "null-space"),
                  "a/b": _modes(rng, n, 1, 1, "kkt")} if variants else {},
        attrs={"units": "N, mm, t, s", "n_rod": 4, "tolerance": 1e-6, "paper_literal": True,
               "ignored_list": [1, 2]},
    )


def assert_same(a, b, where="result"):
    """Recursive exact equality of the plain-data objects (arrays: values, dtype kind, shape)."""
    if dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            assert_same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif sp.issparse(a):
        assert sp.issparse(b) and a.shape == b.shape, where
        assert abs(sp.csr_array(a) - sp.csr_array(b)).sum() == 0, where
    elif isinstance(a, np.ndarray):
        b = np.asarray(b)
        assert a.shape == b.shape, f"{where}: shape {a.shape} != {b.shape}"
        assert a.dtype.kind == b.dtype.kind, f"{where}: dtype {a.dtype} != {b.dtype}"
        np.testing.assert_array_equal(a, b, err_msg=where)
    elif isinstance(a, dict):
        assert list(a) == list(b), f"{where}: keys {list(a)} != {list(b)}"
        for k in a:
            assert_same(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    else:
        assert a == b and type(a) is type(b), f"{where}: {a!r} != {b!r}"


def roundtrip(result: Result, tmp_path: Path) -> Result:
    path = results.save(result, tmp_path / "out" / "r.h5")
    assert path == tmp_path / "out" / "r.h5"
    return results.load(path)


@pytest.mark.parametrize("kw", [
    {},
    {"modes": False},
    {"frf": False},
    {"variants": False},
    {"modes": False, "frf": False, "variants": False},
    {"n_constraints": 0},
    {"n_spurious": 0},
    {"drawings": False},
], ids=lambda kw: ",".join(f"{k}={v}" for k, v in kw.items()) or "full")
def test_round_trip_is_exact(tmp_path, kw):
    r = make_result(**kw)
    back = roundtrip(r, tmp_path)
    expected_attrs = {k: v for k, v in r.attrs.items() if k != "ignored_list"}
    assert {k: back.attrs[k] for k in expected_attrs} == expected_attrs
    assert "ignored_list" not in back.attrs
    assert back.attrs["substruct_version"] == substruct.__version__
    assert isinstance(back.attrs["created"], str) and back.attrs["created"][:2] == "20"
    assert_same(dataclasses.replace(r, attrs={}), dataclasses.replace(back, attrs={}))


def test_round_trip_edge_shapes(tmp_path):
    """Zero constraints, empty spurious, zero modes, float shapes, a glyph-less drawing."""
    r = make_result(n_constraints=0, n_spurious=0)
    r.modes.shapes = r.modes.shapes.real.copy()  # real shapes keep a real dtype
    r.variants = {"empty": dataclasses.replace(
        r.modes, eigenvalues=np.zeros(0, complex), omega=np.zeros(0), damping_ratio=np.zeros(0),
        shapes=np.zeros((7, 0), complex), residual=np.zeros(0), spurious=np.zeros(0, complex),
        spurious_reason=[], agreement={})}
    back = roundtrip(r, tmp_path)
    assert back.model.A.shape == (0, 7) and back.model.b.shape == (0,)
    assert back.modes.spurious.shape == (0,) and back.modes.spurious_reason == []
    assert back.variants["empty"].shapes.shape == (7, 0)
    assert_same(dataclasses.replace(r, attrs={}), dataclasses.replace(back, attrs={}))


def test_layout_is_the_documented_one(tmp_path):
    path = results.save(make_result(), tmp_path / "r.h5")
    with h5py.File(path, "r") as f:
        for key in ("substruct_version", "case_name", "case_yaml", "created", "units", "format"):
            assert key in f.attrs
        assert f.attrs["case_yaml"] == CASE_YAML
        assert f["modes/shapes"].shape == (7, 3) and f["modes/shapes"].dtype.kind == "c"
        assert f["modes/omega"].attrs["units"] == "rad/s"
        assert f["modes"].attrs["agreement_kkt"] == 2.25e-12
        assert f["frf/H"].shape == (5, 2, 3)
        assert list(f["frf/inputs"].asstr()[()]) == ["rod@200", "a@mass", "d@mass"]
        assert h5py.check_string_dtype(f["model/dof_labels"].dtype).encoding == "utf-8"
        assert set(f["model/A"]) == {"data", "indices", "indptr", "shape"}
        assert list(f["variants"]) == ["without constraint (52)", "a_b"]
        assert f["variants/a_b"].attrs["name"] == "a/b"
        assert f["model/drawings/2/cells/0"].attrs["cell_type"] == "tetra"
        assert list(f["model/drawings/1/glyph_names"].asstr()[()]) == ["mass", "boundary",
                                                                      "ground"]


def test_resaving_records_the_current_program(tmp_path):
    r = make_result()
    r.attrs.update(substruct_version="0.0.1", created="1999-01-01", format="x", case_name="y")
    back = roundtrip(r, tmp_path)
    assert back.attrs["substruct_version"] == substruct.__version__
    assert back.attrs["created"] != "1999-01-01"
    assert back.case_name == "synthetic" and "format" not in back.attrs


def test_save_overwrites_and_leaves_no_temporary(tmp_path):
    path = tmp_path / "r.h5"
    results.save(make_result(seed=1), path)
    results.save(make_result(seed=2), path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.h5"]
    assert_same(make_result(seed=2).modes, results.load(path).modes)
    assert oct(path.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_interrupted_write_leaves_nothing(tmp_path, monkeypatch):
    def boom(*args, **kwargs):
        raise RuntimeError("disk full")
    monkeypatch.setattr(results, "_write_frf", boom)
    with pytest.raises(RuntimeError, match="disk full"):
        results.save(make_result(), tmp_path / "r.h5")
    assert list(tmp_path.iterdir()) == []


def test_interrupted_write_keeps_previous_result(tmp_path, monkeypatch):
    path = results.save(make_result(seed=3), tmp_path / "r.h5")
    def interrupted(*args):
        raise KeyboardInterrupt
    monkeypatch.setattr(results, "_write_modes", interrupted)
    with pytest.raises(KeyboardInterrupt):
        results.save(make_result(seed=4), path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.h5"]
    assert_same(make_result(seed=3).modes, results.load(path).modes)


def test_not_hdf5_is_a_clear_error(tmp_path):
    path = tmp_path / "r.h5"
    path.write_text("name: a case file, not a result\n")
    with pytest.raises(ValueError, match=r"r\.h5: not a substruct result: not a readable HDF5"):
        results.load(path)


def test_truncated_file_is_a_clear_error(tmp_path):
    path = results.save(make_result(), tmp_path / "r.h5")
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(ValueError, match=r"r\.h5: not a substruct result"):
        results.load(path)


def test_foreign_hdf5_is_a_clear_error(tmp_path):
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f["x"] = np.arange(3)
    with pytest.raises(ValueError, match=r"other\.h5: not a substruct result: root attribute "
                                         r"'format' is None"):
        results.load(path)


def test_damaged_layout_is_a_clear_error(tmp_path):
    path = results.save(make_result(), tmp_path / "r.h5")
    with h5py.File(path, "a") as f:
        del f["modes/omega"]
    with pytest.raises(ValueError, match=r"not a substruct result: damaged or incomplete"):
        results.load(path)


def test_newer_format_is_refused(tmp_path):
    path = results.save(make_result(), tmp_path / "r.h5")
    with h5py.File(path, "a") as f:
        f.attrs["format_version"] = results.FORMAT_VERSION + 1
    with pytest.raises(ValueError, match="upgrade substruct"):
        results.load(path)


def test_missing_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        results.load(tmp_path / "nope.h5")
