"""Frames made from their case specifications (:mod:`substruct.case.frames`) by
:func:`substruct.models.frame.frame`, and their points (``portal@2:uy``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from substruct.case.frames import FrameSpec
from substruct.models.beam import Material, Section
from substruct.models.frame import Beam, frame
from substruct.models.shell_mesh import Shell
from substruct.substructure import Substructure

__all__ = ["build_frame", "frame_where"]


def build_frame(case: Any, i: int, spec: FrameSpec) -> Substructure:
    """The frame of ``case.substructures[i]``, with its shells.

    Raises:
        CaseError: a member that cannot be made (an orientation along its axis, coincident
            nodes, releases leaving a mechanism), a warped, degenerate or non-convex shell, or a node mass that is not a number or a
            symmetric positive semi-definite 6 x 6 matrix, naming its field.
    """
    sections = {k: Section(A=s.A, Iy=s.Iy, Iz=s.Iz, J=s.J, ky=s.ky, kz=s.kz, Ip=s.Ip)
                for k, s in spec.sections.items()}
    materials = {k: Material(E=m.E, G=m.G, rho=m.rho) for k, m in spec.materials.items()}
    beams = [Beam((int(m.nodes[0]), int(m.nodes[1])), sections[m.section],
                  materials[m.material], (float(m.orientation[0]), float(m.orientation[1]),
                                          float(m.orientation[2])),
                  theory=m.theory, divisions=int(m.divisions), pin_a=m.pin_a, pin_b=m.pin_b,
                  name=str(k))
             for k, m in enumerate(spec.members)]
    shells = [Shell(tuple(int(n) for n in sh.nodes), float(sh.thickness),
                    materials[sh.material], sh.counts(), float(sh.nsm), name=str(k),
                    bending=sh.bending)
              for k, sh in enumerate(spec.shells)]
    masses: dict[int, Any] = {}
    for node, value in spec.node_masses.items():
        try:
            masses[node] = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise case.error(("substructures", i, "node_masses", node), "a node mass is a "
                             "number or a 6 x 6 matrix", value) from None
    nodes = {k: tuple(float(v) for v in xyz) for k, xyz in spec.nodes.items()}
    try:
        return frame(spec.name, nodes, beams, supports=dict(spec.supports), mass=spec.mass,
                     node_masses=masses, shells=shells)
    except ValueError as err:
        text = str(err).split(": ", 1)[-1]  # without the frame's name
        loc: tuple = ("substructures", i)
        for word, key, items in (("member ", "members", spec.members),
                                 ("shell ", "shells", spec.shells)):
            head = text.split(":", 1)[0]
            if head.startswith(word) and head[len(word):].isdigit():
                k = int(head[len(word):])
                raise case.error(loc + (key, k), text.split(": ", 1)[-1],
                                 items[k].model_dump(exclude_defaults=True)) from None
        raise case.error(loc, text) from None


def frame_where(case: Any, spec: FrameSpec, where: str | None, use: Any) -> str:
    """``"node:component"`` of a point on a frame (checked on the built frame)."""
    if where is None or ":" not in where:
        node = next(iter(spec.nodes))
        raise case.error(use.loc, f"a point on frame {spec.name!r} is a node and a component, "
                         f"as in {spec.name}@{node}:uy", use.text)
    return where
