r"""The virtual point transformation (VPT): measured channels around a joint reduced to the six
rigid motions and loads of a virtual point.

A sensor channel ``i`` at position :math:`r_i` with unit direction :math:`e_i` on an interface
that moves rigidly with the virtual point at :math:`r_p` reads (the interface displacement
modes, IDM, of the rigid body: translations :math:`t` and small rotations :math:`\theta`)

.. math::  u_i = e_i^T (t + \theta \times d_i) = [\, e_i^T,\; (d_i \times e_i)^T \,]
           \begin{bmatrix} t \\ \theta \end{bmatrix}, \qquad d_i = r_i - r_p ,

so that the channels of a virtual point read :math:`u = R_u q + \mu` with the ``n x 6`` matrix
:math:`R_u` (one row per channel, more columns for extra flexible modes given per channel) and
a residual :math:`\mu` the rigid motion does not explain.  Its weighted least-squares inverse
is the displacement transformation

.. math::  q = T_u u, \qquad T_u = (R_u^T W_u R_u)^{+} R_u^T W_u .

Impacts at :math:`r_j` in direction :math:`e_j` load the virtual point by the resultant force
and moment :math:`m = R_f^T f` (the same row form); the forces that apply given virtual-point
loads with the least weighted effort are :math:`f = T_f^T m`,

.. math::  T_f = (R_f^T W_f R_f)^{+} R_f^T W_f ,

and the receptance of the virtual points (and of the channels left as they are) is

.. math::  Y_{qm}(\omega) = T_u\, Y(\omega)\, T_f^T .

Channels not assigned to a virtual point pass through (a row of the identity).

The consistency indicators (frequency functions, 1 when the measured motion is rigid) compare
the response filtered through the virtual point with the measured one, for the combined
excitation of the point's own impacts (the sum of their columns, :math:`u = Y 1`) and, for the
impacts, the combined response of its own sensors (:math:`y^T = 1^T Y`):
:math:`\tilde u = F_u u`, :math:`F_u = R_u T_u`, and :math:`\tilde y^T = y^T F_f^T`,
:math:`F_f = R_f T_f`,

.. math::  \rho_u(\omega) = \frac{\lVert \tilde u \rVert}{\lVert u \rVert}, \qquad
           \rho_{u,i}(\omega) = \frac{|\tilde u_i + u_i|^2}{2 (|\tilde u_i|^2 + |u_i|^2)}

(overall, and specific to channel ``i``: 1 when the filtered response equals the measured one,
0 when opposite; likewise :math:`\rho_f`, :math:`\rho_{f,j}` for the impacts).

A virtual point whose :math:`R` has rank below its number of columns (all sensors on one line:
a rotation about that line is unobservable; fewer channels than motions) is refused.  Rank is
decided on :math:`R` with its rotation columns scaled by the channels' root-mean-square
distance from the point, so the decision does not depend on the length unit.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from substruct.case.channels import ChannelTable

__all__ = ["VirtualPoint", "VptResult", "VP_COMPONENTS", "VP_RANK_RTOL", "idm_rows",
           "transformation", "VirtualPointTransform", "virtual_point_transform",
           "consistency", "check_measured"]

#: The six coordinates of a virtual point.
VP_COMPONENTS = ("x", "y", "z", "rx", "ry", "rz")
#: A virtual point's reduction is refused if the smallest singular value of its (length-scaled)
#: ``R`` is below this fraction of the largest.
VP_RANK_RTOL = 1e-8


@dataclass(frozen=True)
class VirtualPoint:
    """A virtual point and the channels that observe and load it.

    Attributes:
        name: its name; its coordinates are labelled ``"<name>:x"`` ... ``"<name>:rz"``.
        position: ``(x, y, z)``.
        sensors, impacts: names of channels in the table.
        extra_u, extra_f: optional extra (flexible) interface modes: ``(n_sensors, k)`` and
            ``(n_impacts, k)`` columns appended to ``R_u`` and ``R_f`` (labelled
            ``"<name>:e1"`` ...; the same ``k`` for both).
        weights_u, weights_f: optional positive channel weights (the diagonal of ``W``).
    """

    name: str
    position: tuple[float, float, float]
    sensors: tuple[str, ...]
    impacts: tuple[str, ...]
    extra_u: np.ndarray | None = None
    extra_f: np.ndarray | None = None
    weights_u: np.ndarray | None = None
    weights_f: np.ndarray | None = None

    def labels(self) -> list[str]:
        """The virtual point's coordinates."""
        k = 0 if self.extra_u is None else self.extra_u.shape[1]
        return [f"{self.name}:{c}" for c in VP_COMPONENTS] + \
            [f"{self.name}:e{i + 1}" for i in range(k)]


def idm_rows(positions: np.ndarray, directions: np.ndarray, point: Sequence[float]
             ) -> np.ndarray:
    r"""The rigid interface displacement modes of channels about a point,
    ``n x 6``: row ``i`` is :math:`[\, e_i^T,\; (d_i \times e_i)^T \,]`, :math:`d_i = r_i - r_p`.
    """
    d = np.asarray(positions, dtype=float) - np.asarray(point, dtype=float)[None, :]
    e = np.asarray(directions, dtype=float)
    return np.hstack([e, np.cross(d, e)])


def transformation(R: np.ndarray, weights: np.ndarray | None, what: str,
                   length: float) -> np.ndarray:
    r""":math:`T = (R^T W R)^{-1} R^T W` of one virtual point (``W = diag(weights)``, the
    identity if ``None``), after checking the rank of ``R`` (module docstring).

    Args:
        R: ``n x c`` (the first six columns rigid, rotations in columns 3-5).
        weights: ``n`` positive weights or ``None``.
        what: names the virtual point and the channel kind in messages.
        length: the channels' root-mean-square distance from the point (scales the rotation
            columns for the rank decision).

    Raises:
        ValueError: fewer channels than columns, a rank-deficient ``R``, bad weights.
    """
    n, c = R.shape
    if n < c:
        raise ValueError(f"{what}: {n} channel(s) cannot determine {c} virtual-point "
                         f"coordinates (at least {c} are needed)")
    w = np.ones(n) if weights is None else np.asarray(weights, dtype=float).ravel()
    if w.shape != (n,) or not np.all(np.isfinite(w)) or not np.all(w > 0):
        raise ValueError(f"{what}: weights must be {n} finite positive numbers")
    scaled = R.copy()
    scaled[:, 3:6] /= max(length, 1e-300)
    s = np.linalg.svd(scaled * np.sqrt(w)[:, None], compute_uv=False)
    rank = int(np.sum(s > VP_RANK_RTOL * s[0]))
    if rank < c:
        raise ValueError(f"{what}: the channels leave {c - rank} virtual-point motion(s) "
                         f"unobservable (rank {rank} of {c}; collinear positions or parallel "
                         f"directions?)")
    RtW = R.T * w[None, :]
    return np.linalg.solve(RtW @ R, RtW)


@dataclass(frozen=True)
class VirtualPointTransform:
    r"""The transformations of one part (module docstring).

    Attributes:
        sensors, impacts: the channel names of the measured receptance's rows and columns.
        out_labels, in_labels: the labels of :math:`Y_{qm}`'s rows and columns (virtual-point
            coordinates first, then the channels that pass through).
        Tu: ``(len(out_labels), len(sensors))``.
        Tf: ``(len(in_labels), len(impacts))``.
        Ru: ``(len(sensors), n_vp)``: the IDM of every sensor (zero rows for those passing
            through), ``n_vp`` the virtual-point coordinates.
        Rf: ``(len(impacts), n_vp)``.
        groups_u, groups_f: for each virtual point, the sensor / impact indices it uses and
            its columns in ``Ru`` / ``Rf`` (its rows in ``Tu`` / ``Tf``).
    """

    sensors: list[str]
    impacts: list[str]
    out_labels: list[str]
    in_labels: list[str]
    Tu: np.ndarray
    Tf: np.ndarray
    Ru: np.ndarray
    Rf: np.ndarray
    groups_u: dict[str, tuple[list[int], list[int]]] = field(default_factory=dict)
    groups_f: dict[str, tuple[list[int], list[int]]] = field(default_factory=dict)

    def apply(self, Y: np.ndarray) -> np.ndarray:
        r""":math:`Y_{qm} = T_u Y T_f^T` at every frequency (``Y``: ``(k, n_s, n_i)``).

        Raises:
            ValueError: ``Y`` of the wrong shape or not finite (:func:`check_measured`).
        """
        check_measured(Y, self.sensors, self.impacts)
        return np.einsum("qs,ksi,mi->kqm", self.Tu, Y, self.Tf, optimize=True)


def _side(table: ChannelTable, points: Sequence[VirtualPoint], channels: Sequence[str],
          kind: str) -> tuple[np.ndarray, np.ndarray, list[str],
                              dict[str, tuple[list[int], list[int]]]]:
    """``T`` and ``R`` of one side (sensors or impacts)."""
    where = {name: i for i, name in enumerate(channels)}
    for name in channels:
        if table.get(name).kind != kind:
            raise ValueError(f"channel {name!r} is a {table.get(name).kind}, not a {kind}")
    used: dict[str, str] = {}
    vp_labels = [lab for p in points for lab in p.labels()]
    n_vp = len(vp_labels)
    R = np.zeros((len(channels), n_vp))
    blocks: list[tuple[int, list[int], np.ndarray]] = []
    groups: dict[str, tuple[list[int], list[int]]] = {}
    col = 0
    for p in points:
        names = p.sensors if kind == "sensor" else p.impacts
        extra = p.extra_u if kind == "sensor" else p.extra_f
        weights = p.weights_u if kind == "sensor" else p.weights_f
        what = f"virtual point {p.name} ({kind}s)"
        for name in names:
            if name not in where:
                raise ValueError(f"{what}: channel {name!r} is not among the measured "
                                 f"{kind}s")
            if name in used:
                raise ValueError(f"{what}: channel {name!r} already belongs to virtual point "
                                 f"{used[name]}")
            used[name] = p.name
        idx = [where[name] for name in names]
        pos, dirs = table.positions(names), table.directions(names)
        Rp = idm_rows(pos, dirs, p.position)
        n_extra = len(p.labels()) - 6
        if n_extra:
            if extra is None or np.shape(extra) != (len(names), n_extra):
                raise ValueError(f"{what}: extra modes of shape ({len(names)}, {n_extra}) "
                                 f"needed, got {None if extra is None else np.shape(extra)}")
            Rp = np.hstack([Rp, np.asarray(extra, dtype=float)])
        length = float(np.sqrt(np.mean(np.sum((pos - np.asarray(p.position)) ** 2, axis=1)))) \
            if len(names) else 0.0
        if length == 0.0:
            length = 1.0  # all at the point: rotations unobservable anyway
        T = transformation(Rp, weights, what, length)
        R[np.ix_(idx, range(col, col + Rp.shape[1]))] = Rp
        blocks.append((col, idx, T))
        groups[p.name] = (idx, list(range(col, col + Rp.shape[1])))
        col += Rp.shape[1]
    passing = [name for name in channels if name not in used]
    T_all = np.zeros((n_vp + len(passing), len(channels)))
    for start, idx, T in blocks:
        T_all[np.ix_(range(start, start + T.shape[0]), idx)] = T
    for k, name in enumerate(passing):
        T_all[n_vp + k, where[name]] = 1.0
    return T_all, R, vp_labels + passing, groups


def virtual_point_transform(table: ChannelTable, points: Sequence[VirtualPoint],
                            sensors: Sequence[str], impacts: Sequence[str]
                            ) -> VirtualPointTransform:
    """The transformations of a part measured at ``sensors`` (rows) and ``impacts`` (columns)
    to the virtual ``points`` (module docstring).

    Raises:
        ValueError: a channel unknown, of the wrong kind or in two virtual points; a
            virtual point's rotations unobservable (collinear sensors or impacts); fewer
            channels than virtual-point coordinates; repeated virtual-point names.
    """
    names = [p.name for p in points]
    if len(set(names)) != len(names):
        raise ValueError(f"virtual point names repeated: {names}")
    for seq, kind in ((sensors, "sensor"), (impacts, "impact")):
        if len(set(seq)) != len(seq):
            raise ValueError(f"a {kind} channel is listed twice")
    Tu, Ru, out_labels, gu = _side(table, points, list(sensors), "sensor")
    Tf, Rf, in_labels, gf = _side(table, points, list(impacts), "impact")
    return VirtualPointTransform(list(sensors), list(impacts), out_labels, in_labels,
                                 Tu, Tf, Ru, Rf, gu, gf)


@dataclass(frozen=True)
class VptResult:
    """The consistency indicators of a transformed part (module docstring), per virtual point.

    Attributes:
        overall_u, overall_f: virtual point -> ``(n_omega,)`` :math:`\\rho_u`, :math:`\\rho_f`.
        specific_u: sensor channel -> ``(n_omega,)`` :math:`\\rho_{u,i}`.
        specific_f: impact channel -> ``(n_omega,)`` :math:`\\rho_{f,j}`.
    """

    overall_u: dict[str, np.ndarray]
    overall_f: dict[str, np.ndarray]
    specific_u: dict[str, np.ndarray]
    specific_f: dict[str, np.ndarray]


def _specific(filtered: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """``|a + b|^2 / (2 (|a|^2 + |b|^2))`` elementwise (1 where both are 0)."""
    num = np.abs(filtered + measured) ** 2
    den = 2 * (np.abs(filtered) ** 2 + np.abs(measured) ** 2)
    out = np.ones_like(num)
    np.divide(num, den, out=out, where=den > 0)
    return out


def consistency(vpt: VirtualPointTransform, Y: np.ndarray) -> VptResult:
    r"""Sensor and impact consistency of a measured receptance ``Y`` (``(k, n_s, n_i)``),
    as frequency functions (module docstring).  Each virtual point's channels are filtered
    through it alone, excited by (or observed through) its own impacts (sensors)."""
    check_measured(Y, vpt.sensors, vpt.impacts)
    over_u, over_f, spec_u, spec_f = {}, {}, {}, {}
    for name, (idx, cols) in vpt.groups_u.items():
        Fu = vpt.Ru[np.ix_(idx, cols)] @ vpt.Tu[np.ix_(cols, idx)]
        u = Y[:, idx][:, :, vpt.groups_f[name][0]].sum(axis=2)  # (k, n)
        uf = u @ Fu.T
        over_u[name] = np.linalg.norm(uf, axis=1) / \
            np.maximum(np.linalg.norm(u, axis=1), 1e-300)
        coh = _specific(uf, u)
        for a, i in enumerate(idx):
            spec_u[vpt.sensors[i]] = coh[:, a]
    for name, (idx, cols) in vpt.groups_f.items():
        Ff = vpt.Rf[np.ix_(idx, cols)] @ vpt.Tf[np.ix_(cols, idx)]
        y = Y[:, vpt.groups_u[name][0]][:, :, idx].sum(axis=1)  # (k, n)
        yf = y @ Ff.T
        over_f[name] = np.linalg.norm(yf, axis=1) / \
            np.maximum(np.linalg.norm(y, axis=1), 1e-300)
        coh = _specific(yf, y)
        for a, j in enumerate(idx):
            spec_f[vpt.impacts[j]] = coh[:, a]
    return VptResult(over_u, over_f, spec_u, spec_f)


def check_measured(Y: np.ndarray, rows: Sequence[str], cols: Sequence[str]) -> None:
    """Refuse a measured receptance of the wrong shape or with a value not finite, naming the
    first such frequency index and channels.

    Raises:
        ValueError: as above.
    """
    if Y.ndim != 3 or Y.shape[1:] != (len(rows), len(cols)):
        raise ValueError(f"measured receptances of shape {list(Y.shape)}, expected "
                         f"(frequencies, {len(rows)}, {len(cols)}) for the channels")
    bad = ~np.isfinite(Y)
    if bad.any():
        k, i, j = (int(v) for v in np.argwhere(bad)[0])
        raise ValueError(f"measured receptance {rows[i]}/{cols[j]} is {Y[k, i, j]} at "
                         f"frequency index {k} ({int(bad.sum())} value(s) not finite)")
