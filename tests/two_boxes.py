"""The case text of two steel boxes ``2 x 0.5 x 0.5`` tied at ``x = 2``, the left one clamped
at ``x = 0`` (about 600 coordinates): the assembly the AMLS and modal-receptance tests run
through ``substruct.run``, each with its own ``analysis`` block."""

from __future__ import annotations


def two_boxes_case(name: str, analysis: str, rayleigh: str | None = None) -> str:
    """The YAML of the tied boxes named ``name``, with ``analysis`` (the lines under
    ``analysis:``, indented by two spaces) and, if given, Rayleigh damping
    ``rayleigh: [alpha, beta]`` (as written in YAML) on both boxes."""
    damping = "" if rayleigh is None else f"    damping: {{rayleigh: {rayleigh}}}\n"
    box = "{lengths: [2.0, 0.5, 0.5], divisions: [8, 3, 3]"
    return (f"name: {name}\n"
            "substructures:\n"
            "  - name: left\n    type: solid\n"
            f"    box: {box}}}\n"
            "    E: 2.1e11\n    nu: 0.3\n    rho: 7850\n    fixed: [xmin]\n" + damping +
            "  - name: right\n    type: solid\n"
            f"    box: {box}, origin: [2, 0, 0]}}\n"
            "    E: 2.1e11\n    nu: 0.3\n    rho: 7850\n" + damping +
            "interfaces:\n"
            "  - {name: a, between: [left, right], nodes: {box: [[2, 0, 0], [2, 0.5, 0.5]]}}\n"
            f"analysis:\n{analysis}"
            "output: {pictures: false}\n")
