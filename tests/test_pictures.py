"""What the mode pictures say (issue 14): coordinates of lumped models labelled, complex shapes
marked, the paper-literal mapping captioned, attachments on solids hung out of the body along
the direction they move in and named."""

from pathlib import Path

import numpy as np
import pytest

import substruct
from substruct.viz.layout import WARP_SPRING, layout
from substruct.viz.mode_picture import complex_part, mapping_note, render_modes

from tolerances import backward_bound

CASES = Path(__file__).resolve().parent.parent / "cases"
BEAM = {
    "name": "beam_tmd",
    "substructures": [
        {"name": "beam", "type": "solid", "E": 2.1e11, "nu": 0.3, "rho": 7850,
         "box": {"lengths": [1.0, 0.1, 0.1], "divisions": [4, 1, 1]}, "fixed": ["xmin"]},
        {"name": "tmd1", "type": "free-free", "mass": 0.5, "stiffness": 2e5, "damping": 50},
        {"name": "tmd2", "type": "free-free", "mass": 0.5, "stiffness": 5e5, "damping": 50}],
    "connections": [["beam@1,0.05,0.1:z", "tmd1"], ["beam@1,0.05,0:z", "tmd2"]],
    "analysis": {"modes": {"count": 2}},
    "output": {"pictures": False},
}


@pytest.fixture
def labels(monkeypatch):
    """The texts the picture puts at points (pyvista's add_point_labels, spied on)."""
    import pyvista as pv

    seen: list[str] = []
    real = pv.Plotter.add_point_labels

    def spy(self, points, texts, *args, **kwargs):
        seen.extend(texts)
        return real(self, points, texts, *args, **kwargs)
    monkeypatch.setattr(pv.Plotter, "add_point_labels", spy)
    return seen


def test_complex_part_is_phase_free_and_bounded():
    u = np.array([1.0, -2.0, 0.5])
    assert complex_part(u) == 0.0
    assert complex_part(u * np.exp(0.7j)) < backward_bound(3)  # a real shape at any phase
    assert complex_part(np.array([1.0, 1j])) == pytest.approx(2 ** -0.5)   # travelling wave


def test_lumped_coordinates_are_labelled(labels):
    result = substruct.run_case(substruct.load_case(CASES / "three_dof_frf.yaml"))
    image = render_modes(result)
    assert image.shape[1] == 1600
    assert labels == ["P@q1", "P@q2", "P@q3"] * 2          # under each of the two modes


def test_paper_literal_shapes_are_captioned():
    literal = substruct.run_case(substruct.load_case(CASES / "tapered_rod_table1.yaml"))
    physical = substruct.run_case(substruct.load_case(CASES / "tapered_rod.yaml"))
    assert "paper-literal mapping" in mapping_note(literal)
    assert "NOT" in mapping_note(literal) and mapping_note(physical) == ""


def test_absorbers_hang_out_of_the_solid_and_are_named(labels):
    result = substruct.run_case(substruct.load_case(BEAM))
    lay = layout(result.model.drawings)
    names = [d.name for d in lay.drawings]
    off = lay.mesh.point_offsets
    p1 = lay.points[off[names.index("tmd1")]:off[names.index("tmd1") + 1]]
    p2 = lay.points[off[names.index("tmd2")]:off[names.index("tmd2") + 1]]
    np.testing.assert_allclose(p1[0], [1, 0.05, 0.1], atol=1e-12)   # at their points
    np.testing.assert_allclose(p2[0], [1, 0.05, 0.0], atol=1e-12)
    # the top one hangs up, the bottom one down, each ending outside the body
    assert p1[1, 2] == pytest.approx(0.1 + WARP_SPRING * lay.size, abs=1e-5)
    assert p2[1, 2] == pytest.approx(0.0 - WARP_SPRING * lay.size, abs=1e-5)
    # and they move along z, the component they are attached to
    d1 = lay.drawings[names.index("tmd1")]
    moved = (d1.interp @ np.ones(d1.interp.shape[1])).reshape(-1, 3)
    assert np.all(moved[:, [0, 1]] == 0) and np.all(moved[:, 2] != 0)
    render_modes(result, n_modes=1)
    assert labels == ["tmd1", "tmd2"]


def test_plate_attachment_at_its_point_moving_along_y():
    result = substruct.run_case(substruct.load_case(CASES / "plate_2d.yaml",
                                                    ["output.pictures=false"]))
    lay = layout(result.model.drawings)
    names = [d.name for d in lay.drawings]
    k = names.index("support")
    p = lay.points[lay.mesh.point_offsets[k]:lay.mesh.point_offsets[k + 1]]
    np.testing.assert_allclose(p[0], [1.0, 0.1, 0.0], atol=1e-9)      # plate@1,0.1:y
    assert p[1, 1] < 0 and p[1, 0] == pytest.approx(1.0)            # ground below the plate
    d = lay.drawings[k]
    moved = (d.interp @ np.ones(d.interp.shape[1])).reshape(-1, 3)
    assert np.all(moved[:, 0] == 0) and np.any(moved[:, 1] != 0)


def test_frf_axes_in_the_case_units():
    from substruct.viz.units import frf_axis_label

    assert frf_axis_label("N, mm, t, s") == "|H|  (displacement / force, mm/N)"
    assert frf_axis_label("N, m, kg, s", "mobility") == "|H|  (velocity / force, m/(N s))"
    assert frf_axis_label("lbf, in, slinch, s", "accelerance") == \
        "|H|  (acceleration / force, in/(lbf s\u00b2))"
    assert frf_axis_label("SI") == "|H|  (displacement / force; case units: SI)"
    assert frf_axis_label(None) == "|H|  (displacement / force)"
    rod = substruct.run_case(substruct.load_case(CASES / "tapered_rod.yaml"))
    assert substruct.frf_figure(rod).axes[0].get_ylabel() == \
        "|H|  (displacement / force, mm/N)"
    three = substruct.run_case(substruct.load_case(CASES / "three_dof_frf.yaml"))
    fig = substruct.frf_figure(three)   # one frequency: matrices, the colour bar says it
    assert "|H|  (displacement / force, m/N)" in [a.get_ylabel() for a in fig.axes]
