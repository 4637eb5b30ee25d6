"""Longitudinally vibrating rods (paper section 6): assumed modes and finite elements.

Both makers discretize the same continuous model (eq 44)

.. math::

    \\bigl(EA(x)\\, u'(x, t)\\bigr)' = m(x)\\, \\ddot u(x, t), \\qquad 0 \\le x \\le L,

with ``EA`` and ``m`` given as numpy-vectorized callables of ``x`` (or constants).  Supports are
named ``"<end at x=0>-<end at x=L>"``: ``"fixed-free"`` (the paper's rod), ``"fixed-fixed"``,
``"free-free"``, ``"free-fixed"``.  Points on a rod are positions ``x`` (a float, or a string
``"x=..."``; :func:`substruct.models.rod_parts.rod_point`); a point outside ``[0, L]`` raises
:class:`PointError`.
The rod is drawn along the global ``x`` axis and displaces along it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementLineP1, ElementLineP2, MeshLine, asm

from substruct.models.rod_parts import (
    SUPPORTS,
    Profile,
    as_profile,
    check_length,
    check_positive,
    check_support,
    drawing_points,
    line_geometry,
    point_label,
    ritz_functions,
    rod_point,
)
from substruct.substructure import PointError, Substructure, as_csr

__all__ = [
    "AssumedModesOptions",
    "SUPPORTS",
    "paper_taper",
    "rod_assumed_modes",
    "rod_fe",
    "uniform_rod_frequencies",
]

def paper_taper(EA0: float, m0: float, L: float) -> tuple[Profile, Profile]:
    """Stiffness and mass distributions of the tapered rod of section 6.

    .. math::  EA(x) = \\tfrac65 EA_0 \\bigl[1 - \\tfrac12 (x/L)^2\\bigr], \\qquad
               m(x) = \\tfrac65 m_0 \\bigl[1 - \\tfrac12 (x/L)^2\\bigr]      \\qquad (50)

    The factor 6/5 makes the mean over ``[0, L]`` of each distribution equal to ``EA0`` and ``m0``.
    For Table 1: ``EA0 = E A = 2e5 * 30 = 6e6``, ``m0 = 1``, ``L = 200``.

    Returns:
        ``(EA, m)``, two numpy-vectorized callables of ``x``.
    """
    EA0, m0, L = float(EA0), float(m0), float(L)

    def EA(x: np.ndarray) -> np.ndarray:
        return 1.2 * EA0 * (1.0 - 0.5 * (np.asarray(x, dtype=float) / L) ** 2)

    def m(x: np.ndarray) -> np.ndarray:
        return 1.2 * m0 * (1.0 - 0.5 * (np.asarray(x, dtype=float) / L) ** 2)

    return EA, m


def uniform_rod_frequencies(EA: float, m: float, L: float, k: int,
                            support: str = "fixed-free") -> np.ndarray:
    """The ``k`` lowest circular frequencies (rad/s) of a uniform rod, closed form.

    With the wave speed :math:`c = \\sqrt{EA/m}` (``m`` mass per unit length),

    .. math::

        \\omega_i = \\frac{(2i-1)\\pi c}{2L} \\ \\text{(fixed-free, free-fixed)}, \\quad
        \\omega_i = \\frac{i\\pi c}{L} \\ \\text{(fixed-fixed)}, \\quad
        \\omega_i = \\frac{(i-1)\\pi c}{L} \\ \\text{(free-free, rigid mode first)},

    for :math:`i = 1, \\dots, k`.
    """
    check_support(support, "uniform rod")
    c = np.sqrt(float(EA) / float(m))
    i = np.arange(1, int(k) + 1, dtype=float)
    factor = {"fixed-free": (2 * i - 1) / 2, "free-fixed": (2 * i - 1) / 2,
              "fixed-fixed": i, "free-free": i - 1}[support]
    return factor * np.pi * c / float(L)


# -------------------------------------------------------------------------- assumed modes


@dataclass(frozen=True)
class AssumedModesOptions:
    """How :func:`rod_assumed_modes` integrates and maps its assumed modes.

    Attributes:
        n_quad_elements: equal elements of the quadrature mesh (``None``: ``max(64, 4 n)``).
        intorder: Gauss integration order on each quadrature element.
        literal_stations: the number ``s`` of stations of the paper-literal mapping (``None``:
            ``n``; at most ``n``, checked by :func:`rod_assumed_modes`).

    Raises:
        ValueError: a count that is not an integer >= 1.
    """

    n_quad_elements: int | None = None
    intorder: int = 24
    literal_stations: int | None = None

    def __post_init__(self) -> None:
        for field, value in (("n_quad_elements", self.n_quad_elements),
                             ("intorder", self.intorder),
                             ("literal_stations", self.literal_stations)):
            if value is None and field != "intorder":
                continue
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ValueError(f"{field} must be an integer >= 1, got {value!r}")


def rod_assumed_modes(name: str, length: float, EA: Profile | float, m: Profile | float,
                      n_modes: int, support: str = "fixed-free", mapping: str = "physical",
                      nodes_at: Sequence[float] = (),
                      options: AssumedModesOptions | None = None) -> Substructure:
    """Rod discretized by assumed modes (Rayleigh-Ritz, eqs 45-49).

    .. math::

        u(x, t) = \\sum_{i=1}^n \\phi_i(x)\\, q_i(t), \\qquad
        m_{ij} = \\int_0^L m\\, \\phi_i \\phi_j \\,dx, \\qquad
        k_{ij} = \\int_0^L EA\\, \\phi_i' \\phi_j' \\,dx          \\qquad (45, 47)

    with the eigenfunctions of the uniform rod with the same supports as Ritz basis:
    ``fixed-free`` :math:`\\sin\\frac{(2i-1)\\pi x}{2L}` (eq 51), ``fixed-fixed``
    :math:`\\sin\\frac{i\\pi x}{L}`, ``free-free`` :math:`\\cos\\frac{(i-1)\\pi x}{L}` (its first
    function is the constant, the rigid-body motion), ``free-fixed``
    :math:`\\cos\\frac{(2i-1)\\pi x}{2L}`.  The integrals (47) are Gauss quadratures of order
    ``intorder`` over a scikit-fem line mesh of ``n_quad_elements`` equal elements (default
    ``max(64, 4 n)``, so each element spans at most about a quarter wavelength of
    :math:`\\phi_i\\phi_j`); relative accuracy is about ``1e-14`` for smooth ``EA`` and ``m``.

    Two mappings from points to coordinates are offered:

    * ``mapping="physical"`` (default): ``locate(x)`` is the row
      :math:`[\\phi_1(x) \\dots \\phi_n(x)]`, i.e. :math:`u(x) = \\sum_i \\phi_i(x) q_i` (eq 45).
    * ``mapping="paper-literal"``: **not physical**; it exists only to reproduce Table 1.
      With ``s = literal_stations`` (default ``n``), the point ``x = j L / s``
      (``j = 1 .. s``, ``s <= n``) is mapped to entry ``j`` of the coordinate vector:
      ``locate(j L / s)`` is the unit row :math:`e_j`, any other ``x`` raises
      :class:`PointError`.  After modal reduction ``q = \\Phi y`` (eq 21) the row becomes
      :math:`\\Phi_{j,:}`, the paper's :math:`\\phi_{ij}` read as "entry ``j`` of the
      ``i``-th eigenvector" (eq 53), as if the assumed-mode amplitudes were nodal displacements
      at ``x = jL/8``.  See docs/verification.md, section 3 (how Table 1 was computed).

    Args:
        name: substructure name.
        length: rod length ``L``.
        EA, m: axial stiffness and mass per unit length: callables of ``x`` or constants.
        n_modes: number ``n`` of assumed modes.
        support: one of :data:`SUPPORTS`.
        mapping: ``"physical"`` or ``"paper-literal"``.
        nodes_at: positions to add to the 201 drawing points and mark as glyphs (the Ritz basis
            does not depend on them).
        options: :class:`AssumedModesOptions`: the quadrature (``n_quad_elements``,
            ``intorder``) and the stations of the paper-literal mapping.

    Returns:
        A :class:`Substructure` with coordinates ``q1 .. qn`` and ``meta`` holding the
        discretization data.
    """
    opts = options or AssumedModesOptions()
    n_quad_elements, intorder = opts.n_quad_elements, opts.intorder
    literal_stations = opts.literal_stations
    L = check_length(name, length)
    check_support(support, name)
    n = int(n_modes)
    if n < 1 or n != n_modes:
        raise ValueError(f"{name}: n_modes must be a positive integer, got {n_modes!r}")
    if mapping not in ("physical", "paper-literal"):
        raise ValueError(f"{name}: mapping must be 'physical' or 'paper-literal', got {mapping!r}")
    ne = int(n_quad_elements) if n_quad_elements is not None else max(64, 4 * n)
    EAf, mf = as_profile(name, "EA", EA), as_profile(name, "m", m)

    basis = Basis(MeshLine(np.linspace(0.0, L, ne + 1)), ElementLineP1(), intorder=intorder)
    xq = basis.mapping.F(basis.X)[0].ravel()
    wq = np.asarray(basis.dx).ravel()
    EAq, mq = EAf(xq), mf(xq)
    check_positive(name, "EA", EAq)
    check_positive(name, "m", mq)
    functions = ritz_functions(support, L, n)
    phi, dphi = functions(xq)
    Mdense = (phi * (mq * wq)) @ phi.T
    Kdense = (dphi * (EAq * wq)) @ dphi.T
    M = as_csr((Mdense + Mdense.T) / 2)
    K = as_csr((Kdense + Kdense.T) / 2)

    meta: dict[str, Any] = {"length": L, "n_modes": n, "support": support, "mapping": mapping,
                            "n_quad_elements": ne, "intorder": intorder}
    if mapping == "physical":
        def locate(where: Any) -> sp.csr_array:
            x = rod_point(name, where, L)
            return sp.csr_array(functions(np.array([x]))[0].T)

        xs, glyphs = drawing_points(L, np.linspace(0.0, L, 201), nodes_at, name)
        geometry = line_geometry(xs, sp.csr_array(functions(xs)[0].T), glyphs)
    else:
        s = n if literal_stations is None else int(literal_stations)
        if not 1 <= s <= n:
            raise ValueError(f"{name}: literal_stations must be in 1..{n} (n_modes), "
                             f"got {literal_stations!r}")
        meta["literal_stations"] = s

        def locate(where: Any) -> sp.csr_array:
            x = rod_point(name, where, L)
            j = round(x * s / L)
            if j < 1 or abs(x - j * L / s) > 1e-9 * L:
                raise PointError(
                    f"{name}: the paper-literal mapping (reproducing Table 1, not physical) only "
                    f"knows the stations x = j L/{s}, j = 1..{s} (L = {L:g}), mapped to "
                    f"coordinate q_j; x = {x!r} is not one of them")
            return sp.csr_array(([1.0], ([0], [j - 1])), shape=(1, n))

        start = 0 if support.startswith("fixed") else 1
        xs = np.arange(start, s + 1) * L / s
        j = np.arange(start, s + 1)
        keep = j >= 1
        rows = sp.csr_array((np.ones(keep.sum()), (np.nonzero(keep)[0], j[keep] - 1)),
                            shape=(len(xs), n))
        marks = [x for x in nodes_at if np.min(abs(xs - rod_point(name, x, L))) <= 1e-9 * L]
        glyphs = {point_label(x): int(np.argmin(abs(xs - float(x)))) for x in marks}
        geometry = line_geometry(xs, rows, glyphs)

    return Substructure(
        name=name, M=M, K=K, C=as_csr(None, n),
        dof_labels=tuple(f"q{i}" for i in range(1, n + 1)), locate=locate,
        kind=f"rod/assumed-modes/{mapping}", geometry=geometry, meta=meta,
    )


# ------------------------------------------------------------------------- finite elements


def _fe_mesh_points(L: float, n_elements: int, marks: Sequence[float]) -> np.ndarray:
    """Mesh nodes: ``0, L`` and ``marks`` are nodes, elements between them of size ~ L/ne."""
    tol = 1e-9 * L
    breaks = np.unique(np.concatenate([[0.0, L], np.asarray(marks, dtype=float)]))
    breaks = breaks[np.concatenate([[True], np.diff(breaks) > tol])]
    breaks[-1] = L
    h = L / n_elements
    pieces = [np.linspace(a, b, max(1, int(round((b - a) / h))) + 1)[:-1]
              for a, b in zip(breaks[:-1], breaks[1:])]
    return np.concatenate(pieces + [[L]])


def rod_fe(name: str, length: float, EA: Profile | float, m: Profile | float,
           n_elements: int, order: int = 1, support: str = "fixed-free",
           nodes_at: Sequence[float] = ()) -> Substructure:
    """Rod discretized by Lagrange finite elements (P1 or P2), consistent mass.

    .. math::

        K = \\sum_e \\int_e EA\\, N'^T N' \\,dx, \\qquad M = \\sum_e \\int_e m\\, N^T N \\,dx,
        \\qquad u(x) = N(x)\\, q

    assembled with scikit-fem (``ElementLineP1`` / ``ElementLineP2``, Gauss order
    ``2 order + 4``, exact for the quadratic taper of eq 50).  Fixed ends are removed by
    Dirichlet condensation: the returned matrices are ``K[f][:, f]``, ``M[f][:, f]`` over the free
    DOFs ``f``.  Eigenvalue errors are :math:`O(h^{2p})` for elements of order ``p``.

    The mesh has elements of size about ``L / n_elements`` and a node at each position of
    ``nodes_at`` (attachment and constraint points): each interval between consecutive such
    points is divided uniformly.  Point springs and point constraints put kinks into the mode
    shapes only at nodes, so they cost no convergence rate.  When ``nodes_at`` lie on the uniform
    grid of ``n_elements`` elements, the mesh is exactly that grid.

    ``locate(x)`` is the interpolation row :math:`N(x)` over the free DOFs (a unit row at a DOF
    location, an all-zero row at a fixed end).  DOF labels are ``"x=<position>"``.

    Args:
        name: substructure name.
        length: rod length ``L``.
        EA, m: axial stiffness and mass per unit length: callables of ``x`` or constants.
        n_elements: target number of elements (the actual number is in ``meta["n_elements"]``).
        order: 1 (P1) or 2 (P2).
        support: one of :data:`SUPPORTS`.
        nodes_at: positions that must be mesh nodes; also marked as drawing glyphs.
    """
    L = check_length(name, length)
    check_support(support, name)
    if int(n_elements) != n_elements or n_elements < 1:
        raise ValueError(f"{name}: n_elements must be a positive integer, got {n_elements!r}")
    if order not in (1, 2):
        raise ValueError(f"{name}: order must be 1 or 2, got {order!r}")
    marks = [rod_point(name, x, L) for x in nodes_at]
    EAf, mf = as_profile(name, "EA", EA), as_profile(name, "m", m)

    mesh = MeshLine(_fe_mesh_points(L, int(n_elements), marks))
    element = ElementLineP1() if order == 1 else ElementLineP2()
    basis = Basis(mesh, element, intorder=2 * order + 4)
    xq = basis.mapping.F(basis.X)[0]
    check_positive(name, "EA", EAf(xq))
    check_positive(name, "m", mf(xq))

    @BilinearForm
    def stiffness(u, v, w):
        return EAf(w.x[0]) * u.grad[0] * v.grad[0]

    @BilinearForm
    def mass(u, v, w):
        return mf(w.x[0]) * u * v

    K_all = sp.csr_array(asm(stiffness, basis))
    M_all = sp.csr_array(asm(mass, basis))
    dofx = basis.doflocs[0]
    tol = 1e-9 * L
    fixed = np.zeros(basis.N, dtype=bool)
    if support.startswith("fixed"):
        fixed |= abs(dofx) <= tol
    if support.endswith("fixed"):
        fixed |= abs(dofx - L) <= tol
    free = np.nonzero(~fixed)[0]
    free = free[np.argsort(dofx[free], kind="stable")]  # coordinates ordered along the rod
    position = -np.ones(basis.N, dtype=int)
    position[free] = np.arange(len(free))
    n = len(free)

    def full_row(x: float) -> sp.csr_array:
        """Interpolation row over all DOFs; exact unit rows at DOF locations."""
        d = int(np.argmin(abs(dofx - x)))
        if abs(dofx[d] - x) <= tol:
            return sp.csr_array(([1.0], ([0], [d])), shape=(1, basis.N))
        row = sp.csr_array(basis.probes(np.array([[x]])))
        row.data[abs(row.data) < 1e-14] = 0.0
        row.eliminate_zeros()
        return row

    def locate(where: Any) -> sp.csr_array:
        """``full_row(x)[:, free]``, its few columns renumbered by ``position`` (a fancy
        index of all ``n`` free columns cost 0.5 ms a point at 8k coordinates)."""
        x = rod_point(name, where, L)
        row = sp.coo_array(full_row(x))
        cols = position[row.col]
        keep = cols >= 0
        return sp.csr_array((row.data[keep], (np.zeros(int(keep.sum()), dtype=int),
                                              cols[keep])), shape=(1, n))

    order_x = np.argsort(dofx, kind="stable")
    xs = dofx[order_x]
    on_free = position[order_x] >= 0  # drawing nodes at fixed ends get all-zero rows
    rows = sp.csr_array((np.ones(on_free.sum()),
                         (np.nonzero(on_free)[0], position[order_x][on_free])),
                        shape=(len(xs), n))
    glyphs = {point_label(x): int(np.argmin(abs(xs - x))) for x in marks}
    geometry = line_geometry(xs, rows, glyphs)

    return Substructure(
        name=name, M=as_csr(M_all[free][:, free]), K=as_csr(K_all[free][:, free]),
        C=as_csr(None, n), dof_labels=tuple(map(point_label, dofx[free].tolist())),
        locate=locate,
        kind=f"rod/fe/P{order}", geometry=geometry,
        meta={"length": L, "order": order, "n_elements": int(mesh.t.shape[1]),
              "h_max": float(np.max(np.diff(mesh.p[0][np.argsort(mesh.p[0])]))),
              "support": support, "nodes_at": [float(x) for x in marks]},
    )
