"""Superelements made from their case specifications (:mod:`substruct.case.superelements`):
the matrices as they were delivered, coordinates labelled ``<grid>:<ux..rz>`` and
``mode:<k>``, points ``sc@100:uz``, ``sc@100:3`` or ``sc@mode:2``, and the boundary grids drawn
where their positions are known."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

from substruct.substructure import Geometry, PointError, Substructure, as_csr

if TYPE_CHECKING:
    from substruct.case.superelements import SuperelementSpec

__all__ = ["build_superelement", "superelement_where", "canonical_label", "RIGID_BODY_ATTR",
           "rigid_body_attrs", "rigid_body_lines"]


def canonical_label(where: Any) -> str | None:
    """``"100:uz"`` for ``"100:uz"``, ``"100:3"`` or ``"100:z"``; ``"mode:2"`` for
    ``"mode:2"``; ``None`` for anything else."""
    from substruct.case.superelements import SE_COMPONENTS  # the schema's: for superelements

    if not isinstance(where, str) or ":" not in where:
        return None
    head, comp = (t.strip() for t in where.split(":", 1))
    if head.lower() == "mode":
        return f"mode:{int(comp)}" if comp.isdigit() else None
    if not head.isdigit():
        return None
    c = comp.lower()
    if c in ("x", "y", "z"):
        c = "u" + c
    if len(c) == 1 and c in "123456":
        c = SE_COMPONENTS[int(c) - 1]
    return f"{int(head)}:{c}" if c in SE_COMPONENTS else None


def _geometry(spec: SuperelementSpec, index: dict[str, int], n: int) -> Geometry | None:
    """The boundary grids as points, moved by their translations."""
    from substruct.case.superelements import SE_COMPONENTS

    if spec.grids is None:
        return None
    ids = sorted(spec.grids)
    points = np.array([spec.grids[g] for g in ids], dtype=float)
    rows, cols = [], []
    for k, g in enumerate(ids):
        for d, c in enumerate(SE_COMPONENTS[:3]):
            j = index.get(f"{g}:{c}")
            if j is not None:
                rows.append(3 * k + d)
                cols.append(j)
    interp = sp.csr_array((np.ones(len(rows)), (rows, cols)), shape=(3 * len(ids), n))
    return Geometry(points=points, cells=[("vertex", np.arange(len(ids)).reshape(-1, 1))],
                    interp=interp, glyphs={str(g): k for k, g in enumerate(ids)})


def build_superelement(case: Any, i: int, spec: SuperelementSpec) -> Substructure:
    """The superelement of ``case.substructures[i]``: ``M``, ``K``, ``C`` (with ``K4 / W4``)
    as read and checked; ``meta`` holds the counts and the rigid-body properties."""
    labels = spec.dof_labels()
    n = len(labels)
    index = {lab: k for k, lab in enumerate(labels)}

    def locate(where: Any) -> sp.csr_array:
        label = canonical_label(where)
        if label is None or label not in index:
            raise PointError(f"{spec.name}: no coordinate {where!r}")
        return sp.csr_array(([1.0], ([0], [index[label]])), shape=(1, n))

    def position(where: Any) -> np.ndarray:
        label = canonical_label(where)
        grids = spec.grids or {}
        if label is None or label.startswith("mode:") or int(label.split(":")[0]) not in grids:
            return np.zeros(3)
        return np.asarray(grids[int(label.split(":")[0])], dtype=float)

    n_modes = sum(1 for lab in labels if lab.startswith("mode:"))
    meta: dict[str, Any] = {"n_dof": n, "n_modes": n_modes, "n_boundary": n - n_modes,
                            "file": spec.file if spec.file is not None else spec.K}
    if spec.rigid_body() is not None:
        meta["rigid_body"] = spec.rigid_body()
    return Substructure(name=spec.name, M=as_csr(spec.matrix("M")), K=as_csr(spec.matrix("K")),
                        C=as_csr(spec.matrix("C"), n), dof_labels=tuple(labels), locate=locate,
                        kind="superelement", geometry=_geometry(spec, index, n), meta=meta,
                        position=position if spec.grids is not None else None)


def superelement_where(case: Any, spec: SuperelementSpec, where: str | None, use: Any) -> str:
    """The coordinate label of a point on a superelement (``100:uz``, ``mode:2``)."""
    label = canonical_label(where)
    labels = spec.dof_labels()
    if label is None or label not in labels:
        shown = ", ".join(labels[:6]) + (" ..." if len(labels) > 6 else "")
        raise case.error(use.loc, f"superelement {spec.name!r} has no coordinate {where!r} "
                         f"(a point is grid:component or mode:k; it has {shown})", use.text)
    return label


#: Prefix of the result attributes holding a superelement's rigid-body properties.
RIGID_BODY_ATTR = "rigid_body:"


def rigid_body_attrs(substructures: Any) -> dict[str, str]:
    """``{"rigid_body:<name>": JSON}`` for each superelement with rigid-body properties:
    ``mass``, ``masses_xyz``, ``cg``, ``inertia_cg``, ``M_rb``, ``reference``,
    ``frequency_ratio``, ``free`` (stored as root attributes of the result file)."""
    import json

    out = {}
    for sub in substructures:
        props = sub.meta.get("rigid_body") if sub.kind == "superelement" else None
        if props:
            out[RIGID_BODY_ATTR + sub.name] = json.dumps(
                {k: (np.asarray(v).tolist() if isinstance(v, np.ndarray) else v)
                 for k, v in props.items()})
    return out


def rigid_body_lines(attrs: Any) -> list[str]:
    """One summary line per superelement with rigid-body properties (see
    :func:`rigid_body_attrs`)."""
    import json

    lines = []
    for key, text in attrs.items():
        if not str(key).startswith(RIGID_BODY_ATTR):
            continue
        p = json.loads(str(text))
        cg = ", ".join(f"{x:.6g}" for x in p["cg"])
        inertia = ", ".join(f"{x:.6g}" for x in np.diag(np.asarray(p["inertia_cg"])))
        ratio = p.get("frequency_ratio")
        free = f", rigid-body frequencies {ratio:.2g} of the first elastic one" \
            if p.get("free") and ratio is not None else ""
        lines.append(f"superelement {key[len(RIGID_BODY_ATTR):]}: rigid-body mass "
                     f"{p['mass']:.6g}, centre of gravity [{cg}], inertia at it "
                     f"(xx, yy, zz) [{inertia}]{free}")
    return lines
