"""The case text of two steel boxes ``2 x 0.5 x 0.5`` tied at ``x = 2``, the left one clamped
at ``x = 0`` (about 600 coordinates): the assembly the AMLS and modal-receptance tests run
through ``substruct.run``, each with its own ``analysis`` block."""

from __future__ import annotations


#: The lines under ``analysis:`` of a modal transient of the tied boxes on an AMLS basis: a
#: half-sine load at the free end, two outputs, checked by the generalized inverse.
AMLS_TRANSIENT = """\
  transient:
    t_end: 0.004
    dt: 5.0e-5
    method: modal
    check: [generalized-inverse]
    tolerance: 1e-2
    loads:
      - {point: "right@4,0.5,0.5:z", shape: half-sine, duration: 0.002, amplitude: 1000}
    outputs: ["right@4,0.5,0.5:z", "left@1,0.5,0.5:y"]
    modal: {solver: amls, cutoff: 0.4, amls: {cutoff: 5, leaf_size: 100}}
"""


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


def tied_boxes(E: float = 2.1e11, nu: float = 0.3, rho: float = 7850.0):
    """The same two boxes built in Python, ``2 x 1 x 1`` each on ``6 x 3 x 3`` Q1 elements
    (the left one clamped at ``x = 0``, tied node to node at ``x = 2``), with two unit inputs
    and three unit outputs on coordinates drawn by a seeded generator: ``(K, M, A, B, O)``,
    ``B`` of ``n x 2`` and ``O`` of ``3 x n``."""
    import numpy as np
    import scipy.sparse as sp

    from substruct.assembly.interfaces import tie_nodes
    from substruct.assembly.stack import assemble
    from substruct.models.solid import BoxGrid, solid_box

    clamp = [{"box": [[0, 0, 0], [0, 1, 1]]}]
    left = solid_box("left", BoxGrid((2.0, 1.0, 1.0), (6, 3, 3)), E, nu, rho, fixed=clamp)
    right = solid_box("right", BoxGrid((2.0, 1.0, 1.0), (6, 3, 3), origin=(2.0, 0, 0)), E, nu,
                      rho)
    asm = assemble([left, right], tie_nodes(left, right, {"box": [[2, 0, 0], [2, 1, 1]]}))
    K, M, A = sp.csr_array(asm.K), sp.csr_array(asm.M), sp.csr_array(asm.A)
    n = K.shape[0]
    rng = np.random.default_rng(1)
    B = np.zeros((n, 2))
    B[rng.choice(n, 2, replace=False), [0, 1]] = 1.0
    O = np.zeros((3, n))
    O[[0, 1, 2], rng.choice(n, 3, replace=False)] = 1.0
    return K, M, A, B, O
