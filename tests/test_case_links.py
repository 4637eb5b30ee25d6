"""Links in case files (``links:``) and Nastran models in case files (``type: nastran``).

A cantilever cut in two halves at coincident nodes, the halves joined by a rigid link, by six
multi-point constraints, or with one half read from bulk data, has the frequencies of the
uncut cantilever (the same elements): the links are exact constraints, so the agreement is to
round-off of the eigensolver, and the two check formulations agree with the main one.
"""

from __future__ import annotations

import numpy as np

from substruct.analysis.api import modes
from substruct.builder.model import assemble_case
from substruct.case.loader import load_case

MAT = {"steel": {"E": 2.1e11, "G": 8.1e10, "rho": 7850.0}}
SEC = {"bar": {"A": 4e-4, "Iy": 5e-8, "Iz": 2e-8, "J": 3e-8}}


def half(name: str, a: int, b: int, xa: float, xb: float, **kw) -> dict:
    return {"name": name, "type": "frame", "nodes": {a: [xa, 0, 0], b: [xb, 0, 0]},
            "materials": MAT, "sections": SEC,
            "members": [{"nodes": [a, b], "section": "bar", "material": "steel",
                         "orientation": [0, 1, 0], "divisions": 8}], **kw}


def omega(case: dict, count: int = 8) -> np.ndarray:
    asm = assemble_case(load_case(case)).assembly
    res = modes(asm.M, None, asm.K, asm.A if asm.A.shape[0] else None, count,
                checks=("null-space", "kkt") if asm.A.shape[0] else ())
    assert not res.agreement or max(res.agreement.values()) < 1e-9
    return res.omega


def reference() -> np.ndarray:
    whole = half("whole", 1, 2, 0.0, 1.0, supports={1: "123456"})
    whole["members"][0]["divisions"] = 16
    return omega({"name": "w", "substructures": [whole], "analysis": {"modes": {"count": 8}}})


def test_rigid_link_and_mpcs_join_two_halves_exactly():
    a = half("a", 1, 2, 0.0, 0.5, supports={1: "123456"})
    b = half("b", 3, 4, 0.5, 1.0)
    ref = reference()
    rigid = {"name": "r", "substructures": [a, b], "analysis": {"modes": {"count": 8}},
             "links": [{"type": "rigid", "independent": "a@2", "dependents": ["b@3"]}]}
    assert np.abs(omega(rigid) / ref - 1).max() < 1e-9
    terms = [{"type": "mpc", "terms": {f"b@3:{c}": 1.0, f"a@2:{c}": -1.0}}
             for c in ("ux", "uy", "uz", "rx", "ry", "rz")]
    mpcs = {**rigid, "links": terms}
    assert np.abs(omega(mpcs) / ref - 1).max() < 1e-9


def test_a_bdf_half_joined_by_a_link_is_the_same_beam(tmp_path):
    lines = ["BEGIN BULK", "PARAM,COUPMASS,1", "MAT1,1,2.1+11,8.1+10,,7850.",
             "PBAR,1,1,4.-4,2.-8,5.-8,3.-8"]
    lines += [f"GRID,{10 + k},,{0.5 + k / 16:.6f},0.,0." for k in range(9)]
    lines += [f"CBAR,{k + 1},1,{10 + k},{11 + k},0.,1.,0." for k in range(8)]
    (tmp_path / "half.bdf").write_text("\n".join(lines + ["ENDDATA", ""]))
    case = {"name": "n", "substructures": [half("a", 1, 2, 0.0, 0.5, supports={1: "123456"}),
                                           {"name": "b", "type": "nastran",
                                            "file": str(tmp_path / "half.bdf")}],
            "links": [{"type": "rigid", "independent": "a@2", "dependents": ["b@10"]}],
            "analysis": {"modes": {"count": 8}}}
    assert np.abs(omega(case) / reference() - 1).max() < 1e-9
