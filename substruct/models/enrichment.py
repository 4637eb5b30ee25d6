r"""Assumed modes enriched with static deflection shapes (a Craig-Bampton-like correction).

The sine basis of :func:`substruct.models.rod.rod_assumed_modes` is smooth: every function has a
continuous slope.  A point spring, an absorber or a point constraint at ``x = a`` puts a jump into
the axial force of the true mode shape,

.. math::  \bigl[EA\, u'\bigr]_{a^-}^{a^+} = -f_a,

which no finite sum of sines has; the Ritz approximation of such a kink converges only like
:math:`1/\sqrt n` in energy, so the eigenvalues converge at first order in ``n``.  Adding to the
basis the static deflection :math:`\psi_a` of the rod under a unit point load at each such point
lets the Ritz method represent the kinks exactly; what is left, :math:`u - \sum_a f_a \psi_a`, has
a continuous axial force and is approximated by the sines at a high rate.

**Static shapes.**  With the axial force :math:`N_a(x)` of a unit load at ``a`` (in ``+x``) and

.. math::  F(x) = \int_0^x \frac{dx'}{EA(x')}, \qquad \mu(x) = \int_0^x m\,dx', \qquad
           G(x) = \int_0^x \frac{\mu(x')}{EA(x')}\,dx',

:math:`\psi_a(x) = \int_0^x N_a / EA \,dx'` (plus a constant), i.e.

* ``fixed-free``: :math:`N_a = H(a - x)`, :math:`\psi_a = F(\min(x, a))`;
* ``free-fixed``: :math:`N_a = -H(x - a)`, :math:`\psi_a = F(L) - F(\max(x, a))`;
* ``fixed-fixed``: :math:`N_a = \nu_a - H(x - a)`,
  :math:`\psi_a = \nu_a F(x) - F(\max(x, a)) + F(a)`, :math:`\nu_a = 1 - F(a)/F(L)`;
* ``free-free``: :math:`N_a = \mu(x)/\mu(L) - H(x - a)`,
  :math:`\psi_a = G(x)/\mu(L) - F(\max(x, a)) + F(a)`

(``free-free``: inertia relief, the unit load balanced by the rod's own d'Alembert forces, since a
free rod has no static response to an unbalanced load).  Each :math:`\psi_a` satisfies the
essential end conditions, and :math:`\psi_a' = N_a/EA` has the jump :math:`-1/EA(a)` at ``a``.
``F``, ``mu`` and ``G`` are computed by composite Gauss-Legendre quadrature (accurate to round-off
for smooth ``EA`` and ``m``); the derivative is the exact :math:`N_a / EA`.

**Orthogonalization.**  With the sines :math:`\phi` (``n``) and the static shapes :math:`\psi`
(``k``), the shapes are first made M-orthogonal to the sines, then M-orthonormal among themselves
by modified Gram-Schmidt (two passes) in the order given:

.. math::

    \tilde\psi = \psi - C^T \phi, \quad M_{\phi\phi} C = M_{\phi\psi}; \qquad
    s_j = \frac{v_j}{\lVert v_j \rVert_M}, \quad
    v_j = \tilde\psi_j - \sum_{i<j,\ \mathrm{kept}} (s_i, \tilde\psi_j)_M\, s_i,

with :math:`(f, g)_M = \int_0^L m f g\,dx`.  A shape with
:math:`\lVert v_j\rVert_M < \mathrm{drop\_tol}\, \lVert\psi_j\rVert_M` (its part outside the span
of the sines and of the shapes kept before it is negligible: a repeated point, a point at a fixed
end) is dropped.  The space spanned is :math:`\mathrm{span}\{\phi, \psi\}` (less the dropped
shapes); only its basis is conditioned.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.models.rod_parts import (
    Profile,
    as_profile,
    check_length,
    check_positive,
    check_support,
    drawing_points,
    line_geometry,
    ritz_functions,
    rod_point,
)
from substruct.substructure import Substructure, as_csr

__all__ = ["static_shapes", "rod_assumed_modes_enriched"]

_GAUSS_POINTS = 16


def _gauss_nodes(edges: np.ndarray, npts: int = _GAUSS_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points and weights on each interval ``[edges[i], edges[i+1]]``."""
    t, w = np.polynomial.legendre.leggauss(npts)
    a, b = edges[:-1, None], edges[1:, None]
    half = (b - a) / 2
    return (a + half * (t + 1)).ravel(), (half * w).ravel()


class _Antiderivative:
    r"""``x -> \int_0^x f`` for a smooth vectorized ``f``: composite Gauss-Legendre.

    The integral is tabulated at ``cells + 1`` equally spaced nodes; a value between nodes adds a
    Gauss rule on ``[node, x]``.  Relative accuracy is round-off for smooth ``f``.
    """

    def __init__(self, f: Callable[[np.ndarray], np.ndarray], L: float, cells: int = 64):
        self.f = f
        self.nodes = np.linspace(0.0, L, cells + 1)
        xq, wq = _gauss_nodes(self.nodes)
        cell = (f(xq) * wq).reshape(cells, -1).sum(axis=1)
        self.table = np.concatenate([[0.0], np.cumsum(cell)])
        self.t, self.w = np.polynomial.legendre.leggauss(_GAUSS_POINTS)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        flat = x.ravel()
        k = np.clip(np.searchsorted(self.nodes, flat, side="right") - 1, 0, len(self.nodes) - 2)
        a = self.nodes[k]
        half = (flat - a) / 2
        pts = a[:, None] + half[:, None] * (self.t[None, :] + 1)
        part = (self.f(pts.ravel()).reshape(pts.shape) * self.w[None, :]).sum(axis=1) * half
        return (self.table[k] + part).reshape(x.shape)


def static_shapes(length: float, EA: Profile | float, m: Profile | float,
                  points: Sequence[float], support: str = "fixed-free"
                  ) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]:
    r"""Static deflections of a rod under unit point loads at ``points`` (module table).

    .. math::  \psi_a(x) = \int_0^x \frac{N_a(x')}{EA(x')}\,dx' + c_a, \qquad
               \psi_a'(x) = \frac{N_a(x)}{EA(x)}

    with :math:`N_a` the axial force of a unit load at ``a`` (``fixed-free``:
    :math:`\psi_a(x) = F(\min(x, a))`, :math:`F = \int_0^x dx'/EA`).  The slope jumps by
    :math:`-1/EA(a)` at ``a``: the kink that a point force causes.

    Args:
        length: rod length ``L``.
        EA, m: stiffness and mass per unit length (callables of ``x`` or constants); ``m`` is
            used only for the inertia relief of a ``free-free`` rod.
        points: load positions ``a`` in ``[0, L]``.
        support: one of :data:`substruct.models.rod.SUPPORTS`.

    Returns:
        ``x -> (psi, dpsi)``, arrays ``(k, len(x))`` of values and slopes (at ``x = a`` the slope
        is the one from the right).
    """
    L = check_length("static shapes", length)
    check_support(support, "static shapes")
    EAf, mf = as_profile("rod", "EA", EA), as_profile("rod", "m", m)
    a = np.array([rod_point("static shapes", x, L) for x in points], dtype=float)[:, None]
    F = _Antiderivative(lambda x: 1.0 / EAf(x), L)
    FL, Fa = float(F(np.array(L))), F(a[:, 0])[:, None]
    if support == "free-free":
        mu = _Antiderivative(mf, L)
        muL = float(mu(np.array(L)))
        G = _Antiderivative(lambda x: mu(x) / EAf(x), L)

    def shapes(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x = np.asarray(x, dtype=float).ravel()[None, :]
        after = (x >= a).astype(float)  # H(x - a)
        Fx = F(x[0])[None, :]
        Fmax = F(np.maximum(x, a).ravel()).reshape(a.shape[0], -1)
        if support == "fixed-free":
            psi = F(np.minimum(x, a).ravel()).reshape(a.shape[0], -1)
            N = 1.0 - after
        elif support == "free-fixed":
            psi = FL - Fmax
            N = -after
        elif support == "fixed-fixed":
            nu = 1.0 - Fa / FL
            psi = nu * Fx - Fmax + Fa
            N = nu - after
        else:
            psi = G(x[0])[None, :] / muL - Fmax + Fa
            N = mu(x[0])[None, :] / muL - after
        return psi, N / EAf(x[0])[None, :]

    return shapes


def rod_assumed_modes_enriched(name: str, length: float, EA: Profile | float,
                               m: Profile | float, n_modes: int, points: Sequence[float],
                               support: str = "fixed-free", n_quad_elements: int | None = None,
                               drop_tol: float = 1e-8,
                               nodes_at: Sequence[float] = ()) -> Substructure:
    r"""Rod by assumed modes enriched with static shapes of unit point loads at ``points``.

    The Ritz basis is :math:`\{\phi_1 \dots \phi_n\} \cup \{s_1 \dots s_{k'}\}`: the uniform-rod
    eigenfunctions of :func:`~substruct.models.rod.rod_assumed_modes` (unchanged) and the static
    shapes :math:`\psi_a` of :func:`static_shapes` made M-orthogonal to them and M-orthonormal
    among themselves (module docstring; ``k' <= k``, near-dependent shapes dropped):

    .. math::

        u(x) = \sum_{i=1}^n \phi_i(x) q_i + \sum_{j=1}^{k'} s_j(x) q_{n+j}, \qquad
        m_{ij} = \int_0^L m\, b_i b_j\,dx, \quad k_{ij} = \int_0^L EA\, b_i' b_j'\,dx

    over all basis functions ``b``.  The integrals are Gauss-Legendre (16 points) on a mesh of
    ``n_quad_elements`` (default ``max(64, 4 n)``) elements with extra nodes at ``points``, so the
    slope jumps of the static shapes fall on element ends and every integrand is smooth.
    The block of the sines equals the matrices of ``rod_assumed_modes`` to round-off; the static
    block has :math:`M_{ss} = I`, :math:`M_{\phi s} = 0`.

    Give as ``points`` every attachment point and every point of a point constraint: each is a
    place where the exact mode shapes have a slope jump.

    Args:
        name: substructure name.
        length: rod length ``L``.
        EA, m: stiffness and mass per unit length: callables of ``x`` or constants.
        n_modes: number ``n`` of sine (uniform-rod) functions.
        points: load positions of the static shapes.
        support: one of :data:`substruct.models.rod.SUPPORTS`.
        n_quad_elements: elements of the quadrature mesh.
        drop_tol: relative M-norm below which a static shape counts as dependent and is dropped.
        nodes_at: extra positions to mark as drawing glyphs (``points`` are always marked).

    Returns:
        A :class:`Substructure` with coordinates ``q1 .. qn, s1 .. sk'``; ``locate(x)`` is the row
        of basis values at ``x``; ``meta["static_points"]`` the kept load points,
        ``meta["dropped_points"]`` the dropped ones, ``meta["static_norm_ratio"]`` for each point
        the M-norm of its shape outside the span of the sines and of the shapes kept before it,
        relative to its M-norm (compared with ``drop_tol``).
    """
    L = check_length(name, length)
    check_support(support, name)
    n = int(n_modes)
    if n < 1 or n != n_modes:
        raise ValueError(f"{name}: n_modes must be a positive integer, got {n_modes!r}")
    pts = [rod_point(name, x, L) for x in points]
    if not pts:
        raise ValueError(f"{name}: an enriched basis needs at least one load point")
    ne = int(n_quad_elements) if n_quad_elements is not None else max(64, 4 * n)
    if ne < 1:
        raise ValueError(f"{name}: n_quad_elements must be positive, got {n_quad_elements!r}")
    EAf, mf = as_profile(name, "EA", EA), as_profile(name, "m", m)

    edges = np.unique(np.concatenate([np.linspace(0.0, L, ne + 1), pts]))
    edges = edges[np.concatenate([[True], np.diff(edges) > 1e-12 * L])]
    xq, wq = _gauss_nodes(edges)
    EAq, mq = EAf(xq), mf(xq)
    check_positive(name, "EA", EAq)
    check_positive(name, "m", mq)
    sines = ritz_functions(support, L, n)
    statics = static_shapes(L, EAf, mf, pts, support)
    phi, dphi = sines(xq)
    psi, dpsi = statics(xq)

    # orthogonalize the static shapes against the sines in the M inner product, then against
    # each other (modified Gram-Schmidt, two passes); the same operations on the coefficients
    # over the raw functions [phi; psi] give E with basis = E^T [phi; psi]
    wm = mq * wq
    Mpp = (phi * wm) @ phi.T
    Mps = (phi * wm) @ psi.T
    C = sla.solve((Mpp + Mpp.T) / 2, Mps, assume_a="pos")
    k = len(pts)
    vals = psi - C.T @ phi
    dvals = dpsi - C.T @ dphi
    coef = np.vstack([-C, np.eye(k)])  # (n + k) x k
    norm = np.sqrt(np.einsum("ij,ij->i", psi * wm, psi))
    kept: list[int] = []
    ratio = np.zeros(k)
    for j in range(k):
        for _ in range(2):
            for i in kept:
                c = float((vals[i] * wm) @ vals[j])
                vals[j] -= c * vals[i]
                dvals[j] -= c * dvals[i]
                coef[:, j] -= c * coef[:, i]
        size = float(np.sqrt((vals[j] * wm) @ vals[j]))
        ratio[j] = size / norm[j] if norm[j] > 0 else 0.0
        if ratio[j] > drop_tol:
            vals[j] /= size
            dvals[j] /= size
            coef[:, j] /= size
            kept.append(j)
    kk = len(kept)
    E = np.zeros((n + k, n + kk))
    E[:n, :n] = np.eye(n)
    E[:, n:] = coef[:, kept]

    b = np.vstack([phi, vals[kept]])
    db = np.vstack([dphi, dvals[kept]])
    Md = (b * wm) @ b.T
    Kd = (db * (EAq * wq)) @ db.T
    M = as_csr((Md + Md.T) / 2)
    K = as_csr((Kd + Kd.T) / 2)

    def values(x: np.ndarray) -> np.ndarray:
        """Basis values ``(n + k', len(x))``."""
        return E.T @ np.vstack([sines(x)[0], statics(x)[0]])

    def locate(where: Any) -> sp.csr_array:
        x = rod_point(name, where, L)
        return sp.csr_array(values(np.array([x])).T)

    dropped = [p for j, p in enumerate(pts) if j not in kept]
    xs, glyphs = drawing_points(L, np.linspace(0.0, L, 201), list(pts) + list(nodes_at), name)
    geometry = line_geometry(xs, sp.csr_array(values(xs).T), glyphs)
    meta: dict[str, Any] = {
        "length": L, "n_modes": n, "support": support, "mapping": "physical",
        "n_quad_elements": len(edges) - 1, "static_points": [float(pts[j]) for j in kept],
        "n_static": kk, "dropped_points": [float(p) for p in dropped],
        "static_norm_ratio": ratio.tolist(), "drop_tol": drop_tol,
    }
    labels = tuple(f"q{i}" for i in range(1, n + 1)) + tuple(f"s{j}" for j in range(1, kk + 1))
    return Substructure(
        name=name, M=M, K=K, C=as_csr(None, n + kk), dof_labels=labels, locate=locate,
        kind="rod/assumed-modes/enriched", geometry=geometry, meta=meta,
    )
