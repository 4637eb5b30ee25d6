r"""A model written back as matrices for other tools: the coupled model of a result, or one of
its parts, as OP4 (:func:`substruct.io.op4.write_op4`) or NPZ, with its DOF map.

The result must hold its matrices (``output: {matrices: true}``).  A part is its block of the
stacked matrices (eq 23), as reduced in the run.  The coupled model is the stacked one with its
constraints eliminated (:func:`substruct.linalg.nullspace.master_slave`): :math:`q = T p` with
:math:`A T = 0`, ``T[masters] = I``, and

.. math::  M_p = T^T M T, \quad K_p = T^T K T, \quad C_p = T^T C T

over the master coordinates, which keep their labels; constraints with a right-hand side
:math:`b \ne 0` are not a linear model and are refused.

The DOF map gives each coordinate's ``(grid, component)``: a label ``<grid>:<ux..rz>`` (or a
digit 1-6) is that grid's component; ``mode:<k>`` or ``eta<k>`` a modal coordinate (component
0, grid 0); any other label cannot be mapped and is refused, as is one grid component held by
two parts of a coupled model.  Members: OP4 ``MAA``, ``KAA``, ``BAA`` (if damped), ``DOFS``
(``n x 2``); NPZ ``M``, ``K``, ``C`` (if damped), ``DOFS``, ``labels`` (the full labels) and,
when the case declares its ``units``, ``units`` (that text), which a case reading the file back
must declare alike (:mod:`substruct.case.superelements`).  Read back by ``type: superelement``
with ``dofs: {key: DOFS}``.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from substruct.case.errors import CaseError
from substruct.case.yaml_io import load_yaml
from substruct.io.op4 import write_op4
from substruct.io.paths import safe_stem
from substruct.linalg.nullspace import master_slave
from substruct.run.result import Result

__all__ = ["ExportedModel", "exported_model", "case_units", "dof_map", "model_path", "write_model",
           "MODEL_FORMATS"]

#: The formats a model is written in.
MODEL_FORMATS = ("op4", "npz")
_COMPONENTS = ("ux", "uy", "uz", "rx", "ry", "rz")


@dataclass
class ExportedModel:
    """Matrices over the exported coordinates, their labels and DOF map (``n x 2``)."""

    M: sp.csr_array
    K: sp.csr_array
    C: sp.csr_array
    labels: list[str]
    dofs: np.ndarray
    units: str = ""


def dof_map(labels: list[str]) -> np.ndarray:
    """``(grid, component)`` of each label (module docstring), ``(0, 0)`` for modal ones.

    Raises:
        ValueError: a label that names no grid component or mode; a grid component twice.
    """
    out: list[tuple[int, int]] = []
    seen: dict[tuple[int, int], str] = {}
    for lab in labels:
        local = lab.split(".", 1)[1] if "." in lab else lab
        m = re.fullmatch(r"(\d{1,9}):(ux|uy|uz|rx|ry|rz|[1-6])", local)
        if m:
            g = int(m[1])
            c = int(m[2]) if m[2].isdigit() else _COMPONENTS.index(m[2]) + 1
            if (g, c) in seen:
                raise ValueError(f"grid {g} component {c} is both {seen[g, c]!r} and {lab!r}: "
                                 "export one part at a time (--part)")
            seen[g, c] = lab
            out.append((g, c))
        elif re.fullmatch(r"mode:\d+|eta\d+", local):
            out.append((0, 0))
        else:
            raise ValueError(f"coordinate {lab!r} is neither <grid>:<component> nor a mode: "
                             "a DOF map cannot name it")
    return np.array(out, dtype=np.int64).reshape(-1, 2)


def case_units(case_yaml: str) -> str:
    """The ``units`` a result's case file declares (``""`` if none or unreadable)."""
    try:
        data = load_yaml(case_yaml, "<case>")
    except CaseError:
        return ""
    units = data.get("units") if isinstance(data, dict) else None
    return units.strip() if isinstance(units, str) else ""


def exported_model(result: Result, part: str | None = None) -> ExportedModel:
    """The part ``part`` of ``result`` (its block), or the coupled model (constraints
    eliminated) if ``None``.

    Raises:
        ValueError: no matrices in the result, an unknown part, constraints with a non-zero
            right-hand side, labels with no DOF map.
    """
    model = result.model
    if not model.matrices:
        raise ValueError(f"result of {result.case_name!r} holds no matrices: run the case with "
                         "output: {matrices: true}")
    M, K = model.matrices["M"], model.matrices["K"]
    C = model.matrices.get("C", sp.csr_array(M.shape))
    if part is not None:
        if part not in model.substructure_names:
            raise ValueError(f"--part {part!r} is not a part of the model (it has "
                             f"{', '.join(model.substructure_names)})")
        i = model.substructure_names.index(part)
        blk = slice(int(model.offsets[i]), int(model.offsets[i + 1]))
        labels = [lab.split(".", 1)[1] if lab.startswith(part + ".") else lab
                  for lab in model.dof_labels[blk]]
        return ExportedModel(sp.csr_array(M[blk][:, blk]), sp.csr_array(K[blk][:, blk]),
                             sp.csr_array(C[blk][:, blk]), labels, dof_map(labels),
                             case_units(result.case_yaml))
    if model.A.shape[0] and np.any(np.asarray(model.b) != 0):
        raise ValueError("the constraints have a non-zero right-hand side b: the coupled "
                         "model is not linear in its coordinates; export a part (--part)")
    labels = list(model.dof_labels)
    if model.A.shape[0]:
        elim = master_slave(model.A)
        T = sp.csr_array(elim.T)
        labels = [labels[k] for k in elim.masters]

        def project(X: sp.csr_array) -> sp.csr_array:
            P = sp.csr_array(T.T @ (X @ T))
            return sp.csr_array((P + P.T) / 2)

        M, K, C = project(M), project(K), project(C)
    return ExportedModel(sp.csr_array(M), sp.csr_array(K), sp.csr_array(C), labels,
                         dof_map(labels), case_units(result.case_yaml))


def model_path(result: Result, out: str | os.PathLike, fmt: str, part: str | None) -> Path:
    """``<case>_model.<fmt>`` or ``<case>_<part>.<fmt>`` in the folder ``out``."""
    tail = safe_stem(part, "part") if part is not None else "model"
    return Path(out) / f"{safe_stem(result.case_name)}_{tail}.{fmt}"


def write_model(model: ExportedModel, path: str | os.PathLike, fmt: str) -> None:
    """Write ``model`` to ``path`` as ``fmt`` (module docstring: the members)."""
    if fmt not in MODEL_FORMATS:
        raise ValueError(f"format must be one of {', '.join(MODEL_FORMATS)}, got {fmt!r}")
    damped = model.C.nnz and bool(np.any(model.C.data))
    if fmt == "op4":
        mats = {"MAA": model.M.toarray(), "KAA": model.K.toarray()}
        if damped:
            mats["BAA"] = model.C.toarray()
        mats["DOFS"] = model.dofs.astype(float)
        write_op4(path, mats, binary=True, forms={"MAA": 6, "KAA": 6, "BAA": 6})
        return
    arrays = {"M": model.M.toarray(), "K": model.K.toarray(), "DOFS": model.dofs,
              "labels": np.array(model.labels, dtype=str)}
    if damped:
        arrays["C"] = model.C.toarray()
    if model.units:
        arrays["units"] = np.array(model.units, dtype=str)
    with open(path, "wb") as fp:
        np.savez(fp, **arrays)
