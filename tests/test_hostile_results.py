"""Hostile result files for ``info`` and ``export``: one line, exit 2, never a traceback, never
a VTU whose cells point past its points, nothing allocated from what a file only declares.

Each case starts from a good result file (the synthetic rod + tetra model of
``tests/test_export.py``) and breaks one thing with h5py.
"""

from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest

from cli_helpers import run
from substruct.io import hdf5 as results
from test_export import make_result


def _set(path, value):
    def mutate(f):
        attrs = dict(f[path].attrs) if isinstance(f[path], h5py.Dataset) else {}
        del f[path]
        f[path] = value
        f[path].attrs.update(attrs)
    return mutate


def _attr(path, key, value):
    def mutate(f):
        f[path].attrs[key] = value
    return mutate


def _huge(path, shape, dtype):
    def mutate(f):
        del f[path]
        f.create_dataset(path, shape=shape, dtype=dtype, chunks=True)  # nothing stored
    return mutate


def _link(path, link):
    def mutate(f):
        del f[path]
        f[path] = link
    return mutate


def _truncate(fraction):
    def damage(p: Path):
        data = p.read_bytes()
        p.write_bytes(data[: int(len(data) * fraction)])
    return damage


CELLS = "model/drawings/1/cells/0"  # the two tetrahedra
CASES = {
    "truncated_half": (_truncate(0.5), "not a readable HDF5 file"),
    "truncated_empty": (_truncate(0.0), "not a readable HDF5 file"),
    "omega_longer": (_set("modes/omega", np.arange(4.0)), "/modes/eigenvalues has shape (3,)"),
    "shapes_1d": (_set("modes/shapes", np.zeros(21, complex)), "/modes/shapes has shape (21,)"),
    "shapes_wrong_rows": (_set("modes/shapes", np.zeros((22, 3), complex)),
                          "/modes/shapes has shape (22, 3), expected (21, 3)"),
    "H_wrong_shape": (_set("frf/H", np.zeros((2, 2, 2), complex)), "/frf/H has shape"),
    "soft_link_loop": (_link("modes", h5py.SoftLink("/modes")), "/modes is a SoftLink"),
    "soft_link_loop_deep": (_link("model/drawings/0/points",
                                  h5py.SoftLink("/model/drawings/0/points")),
                            "points is a SoftLink"),
    "external_link": (_link("model", h5py.ExternalLink("/etc/passwd", "/x")),
                      "/model is a ExternalLink"),
    "unknown_cell_type": (_attr(CELLS, "cell_type", "hexagon"), "unknown cell type 'hexagon'"),
    "cell_past_points": (_set(CELLS, np.array([[0, 1, 2, 3], [1, 2, 3, 99]])),
                         "points at point 99, of 5 points"),
    "cell_negative": (_set(CELLS, np.array([[0, 1, 2, 3], [1, 2, 3, -1]])),
                      "points at point -1"),
    "cell_wrong_nodes": (_set(CELLS, np.array([[0, 1, 2], [1, 2, 3]])), "has shape (2, 3)"),
    "cells_float": (_set(CELLS, np.array([[0.0, 1, 2, 3]])), "holds float64 values"),
    "shapes_3GB": (_huge("modes/shapes", (21, 9_000_000), complex),
                   "declares (21, 9000000) x complex128 (3.02 GB), more than the 1 GB"),
    "omega_3GB": (_huge("modes/omega", (400_000_000,), float), "(3.2 GB)"),
    "labels_3GB": (_huge("model/dof_labels", (200_000_000,), h5py.string_dtype()),
                   "(3.2 GB)"),
    "interp_index_past_columns": (_set("model/drawings/0/interp/indices",
                                       np.array([0, 1, 2, 3, 4, 10 ** 6])),
                                 "holds column 1000000 of a matrix of 21 columns"),
    "interp_indptr_backwards": (_set("model/drawings/0/interp/indptr",
                                     np.array([0, 3, 1] + [6] * 19)), "is not a row pointer"),
    "offsets_past_end": (_set("model/offsets", np.array([0, 6, 40])),
                         "offsets does not split the 21 coordinates"),
    "glyph_past_points": (_set("model/drawings/0/glyph_indices", np.array([70])),
                          "glyph_indices points past the 7 points"),
    "points_nan": (_set("model/drawings/1/points", np.full((5, 3), np.nan)), "not finite"),
    "points_1d": (_set("model/drawings/1/points", np.zeros(15)), "has shape (15,)"),
    "labels_not_strings": (_set("model/dof_labels", np.zeros(21)), "holds float64 values"),
    "no_format": (lambda f: f.attrs.__delitem__("format"), "root attribute 'format' is None"),
    "format_version_text": (_attr("/", "format_version", "one"), "damaged or incomplete"),
    "variant_is_dataset": (_set("variants/half", np.zeros(3)), "/variants/half is not a group"),
    "drawing_not_numbered": (lambda f: f.move("model/drawings/1", "model/drawings/x"),
                             "holds a member that is not numbered"),
    "frf_negative_frequency": (_set("frf/omega", np.array([-1.0, 2.0, 3.0])),
                               "/frf/omega holds the negative frequency -1.0"),
    "frf_label_100k": (_set("frf/outputs", np.array(["x" * 100_000], dtype=object).astype(
        h5py.string_dtype())), "/frf/outputs[0] is a label of 100000 characters"),
}


def hostile(tmp_path: Path, name: str) -> Path:
    path = results.save(make_result(), tmp_path / "r.h5")
    with h5py.File(path, "a") as f:  # a frf block so that /frf cases have something to break
        g = f.create_group("frf")
        g.attrs.update(method="kkt", constraint_residual=0.0)
        g["omega"] = np.arange(1.0, 4.0)
        g["H"] = np.zeros((3, 1, 1), complex)
        g["inputs"] = np.array(["rod@1"], dtype=object).astype(h5py.string_dtype())
        g["outputs"] = np.array(["rod@1"], dtype=object).astype(h5py.string_dtype())
    assert results.load(path).frf is not None  # the starting point is good
    mutate, _ = CASES[name]
    if mutate.__name__ == "damage":
        mutate(path)
    else:
        with h5py.File(path, "a") as f:
            mutate(f)
    return path


@pytest.mark.parametrize("name", sorted(CASES))
def test_info_and_export_refuse_in_one_line(name, tmp_path, capsys):
    path = hostile(tmp_path, name)
    fragment = CASES[name][1]
    for args in (["info", path], ["info", path, "--json"],
                 ["export", path, "--format", "vtu", "--out", tmp_path / "vtu"]):
        code, out, err = run(capsys, *args)
        assert code == 2 and out == "", (args, err)
        assert err.startswith(f"substruct: error: {path}: not a substruct result: "), err
        assert err.count("\n") == 1 and "Traceback" not in err
        assert fragment in err, err
    assert not (tmp_path / "vtu").exists()


def test_at_least_twenty_hostile_files():
    assert len(CASES) >= 20


def test_huge_mode_range_is_refused_before_any_list(tmp_path, capsys):
    path = results.save(make_result(), tmp_path / "r.h5")
    code, out, err = run(capsys, "export", path, "--format", "vtu", "--modes",
                         "1-99999999999999", "--out", tmp_path / "x")
    assert (code, out) == (2, "")
    assert err == ("substruct: error: --modes: no mode 4; the result has 3 modes (numbered 1 "
                   "to 3)\n")
    assert not (tmp_path / "x").exists()


def test_info_escapes_control_characters(tmp_path, capsys):
    r = make_result()
    r.attrs["description"] = "evil\x1b]0;owned\x07\x1b[2J tail"
    r.model.substructure_names = ["rod\u202e", "block"]
    path = results.save(r, tmp_path / "r.h5")
    code, out, err = run(capsys, "info", path)
    assert code == 0, err
    assert "\x1b" not in out and "\x07" not in out and "\u202e" not in out
    assert "description: evil\\x1b]0;owned\\x07\\x1b[2J tail" in out
    assert "substructure rod\\u202e: rod/fe-P1, 6 coordinate(s)" in out


def test_exported_vtu_reads_back_with_cells_inside_its_points(tmp_path, capsys):
    path = results.save(make_result(), tmp_path / "r.h5")
    code, out, err = run(capsys, "export", path, "--format", "vtu", "--out", tmp_path / "v")
    assert code == 0, err
    mesh = meshio.read(out.split()[0])
    assert len(mesh.points) == 12
    assert all(c.data.max() < len(mesh.points) for c in mesh.cells)
