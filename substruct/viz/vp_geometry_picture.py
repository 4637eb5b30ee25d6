r"""The virtual-point geometry picture (matplotlib, 3D): for every ``type: frf`` part with
``virtual_points:``, the channel table the run used and the virtual points.

One 3D axis per part, in that part's own coordinates (the channel table's):

* each sensor channel :math:`i` a point at its position :math:`\mathbf r_i` with a short arrow
  along its direction :math:`\mathbf e_i` (blue dots);
* each impact channel :math:`j` likewise at :math:`\mathbf r_j` along :math:`\mathbf e_j`
  (red triangles, the arrow the force's direction);
* each virtual point a larger black diamond at its ``position``, named.

The arrows are :math:`\mathbf r \to \mathbf r + \ell\,\mathbf e` with :math:`\ell` a tenth of the
largest extent of the part's points (a twentieth of a unit when they all coincide), so the
picture does not depend on the units; the axes have equal aspect, so directions are drawn
true.  :func:`vp_geometry` collects the numbers drawn from a case, :func:`geometry_of` from the
``/channels`` a result keeps; :func:`draw_vp_geometry` draws them;
:func:`plot_vp_geometry` writes the PNG (atomically) and returns the path.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from substruct.io.hdf5 import atomic_path

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from substruct.case.channel_geometry import PartChannels

__all__ = ["PartGeometry", "geometry_of", "vp_geometry", "arrow_length", "draw_vp_geometry",
           "plot_vp_geometry"]


@dataclass(frozen=True)
class PartGeometry:
    """The channels and virtual points of one part, as drawn.

    Attributes:
        sensors, impacts: channel names, in the channel table's order.
        sensor_xyz, impact_xyz: ``(n, 3)`` positions.
        sensor_dir, impact_dir: ``(n, 3)`` unit directions.
        points: virtual-point names; ``point_xyz``: ``(n_vp, 3)`` their positions.
    """

    sensors: list[str]
    sensor_xyz: np.ndarray
    sensor_dir: np.ndarray
    impacts: list[str]
    impact_xyz: np.ndarray
    impact_dir: np.ndarray
    points: list[str]
    point_xyz: np.ndarray


def geometry_of(channels: dict[str, PartChannels]) -> dict[str, PartGeometry]:
    """Part name -> :class:`PartGeometry` of the channel geometry a result keeps
    (:attr:`substruct.run.result.Result.channels`, read back from ``/channels``)."""
    out: dict[str, PartGeometry] = {}
    for part, pc in channels.items():
        sen, imp = pc.table.of_kind("sensor"), pc.table.of_kind("impact")

        def rows(chans: list[Any], attr: str) -> np.ndarray:
            return np.asarray([getattr(c, attr) for c in chans], dtype=float).reshape(-1, 3)

        out[part] = PartGeometry(
            [c.name for c in sen], rows(sen, "position"), rows(sen, "direction"),
            [c.name for c in imp], rows(imp, "position"), rows(imp, "direction"),
            list(pc.points), np.asarray(pc.point_xyz, dtype=float).reshape(-1, 3))
    return out


def vp_geometry(case: Any) -> dict[str, PartGeometry]:
    """Part name -> :class:`PartGeometry` for every substructure of ``case`` with
    ``virtual_points:`` (the channel table read when the case was loaded)."""
    from substruct.case.channel_geometry import case_channels

    return geometry_of(case_channels(case))


def arrow_length(g: PartGeometry) -> float:
    """A tenth of the largest extent of the part's points (0.05 when they coincide)."""
    xyz = np.vstack([g.sensor_xyz, g.impact_xyz, g.point_xyz])
    extent = float(np.ptp(xyz, axis=0).max()) if len(xyz) else 0.0
    return 0.1 * extent if extent > 0 else 0.05


def draw_vp_geometry(geometry: dict[str, PartGeometry], title: str = "") -> Figure:
    """One 3D axis per part: sensors, impacts (points and arrows) and virtual points, with
    a legend (module docstring).  The artists are labelled ``sensors``, ``impacts``,
    ``virtual points`` (points) and ``sensor directions``, ``impact directions`` (arrows).

    Raises:
        ValueError: ``geometry`` is empty.
    """
    from matplotlib.figure import Figure

    if not geometry:
        raise ValueError("no part with virtual points to draw")
    n = len(geometry)
    fig = Figure(figsize=(6.2 * n, 6.0), dpi=110, layout="constrained")
    for k, (part, g) in enumerate(geometry.items()):
        ax = fig.add_subplot(1, n, k + 1, projection="3d")
        ell = arrow_length(g)
        for xyz, d, colour, marker, what in (
                (g.sensor_xyz, g.sensor_dir, "C0", "o", "sensor"),
                (g.impact_xyz, g.impact_dir, "C3", "^", "impact")):
            if not len(xyz):
                continue
            ax.scatter(xyz[:, 0], xyz[:, 1], xyz[:, 2], color=colour, marker=marker, s=22,
                       depthshade=False, label=f"{what}s")
            ax.quiver(xyz[:, 0], xyz[:, 1], xyz[:, 2], d[:, 0], d[:, 1], d[:, 2],
                      length=ell, normalize=False, color=colour, lw=1.0,
                      arrow_length_ratio=0.25, label=f"{what} directions")
        p = g.point_xyz
        ax.scatter(p[:, 0], p[:, 1], p[:, 2], color="k", marker="D", s=90, depthshade=False,
                   label="virtual points")
        for name, (x, y, z) in zip(g.points, p):
            ax.text(x, y, z, f"  {name}", fontsize="small")
        ax.set_aspect("equal")
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        ax.set_zlabel("z")
        ax.set_title(f"{part}: {len(g.sensors)} sensors, {len(g.impacts)} impacts, "
                     f"{len(g.points)} virtual point(s)")
        ax.legend(fontsize="small", loc="upper left")
    if title:
        fig.suptitle(title)
    return fig


def plot_vp_geometry(geometry: dict[str, PartGeometry], png_path: str | os.PathLike,
                     title: str = "") -> Path:
    """:func:`draw_vp_geometry` written as PNG; return the path."""
    path = Path(png_path)
    fig = draw_vp_geometry(geometry, title)
    with atomic_path(path, suffix=".png.part") as tmp:
        fig.savefig(tmp, format="png")
    return path
