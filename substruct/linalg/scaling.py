r"""Sizes of rows and columns: row equilibration of constraints, the mass scale of coordinates.

A constraint ``1e-8 q_1 = 0`` says what ``q_1 = 0`` says.  Every decision on rank and consistency
is therefore taken on *equilibrated* rows, each scaled to unit 2-norm (to the nearest power of
two, :class:`RowScale`),

.. math::  D A q = D b + D R F, \qquad D = \operatorname{diag}(d_i), \quad
           d_i \approx \frac{1}{s_i \nu_i}, \quad s_i = \max_j |a_{ij}|, \quad
           \nu_i = \Big\| \frac{a_i}{s_i} \Big\|_2 \in [1, \sqrt{n}],

which changes neither the solutions nor the constrained motion.  The largest entry is divided
out *before* the 2-norm is taken, so a row ``1e-300 q_1`` becomes ``q_1`` instead of underflowing
to zero (:math:`(10^{-300})^2 = 0` in floating point).  A row that is exactly zero constrains
nothing: it is refused (:class:`ZeroRowError`), never dropped in silence.

Columns are scaled by the mass, :math:`c_j = (\bar m / m_{jj})^{1/2}` (:func:`mass_column_scale`),
when the rank of the rows is decided: :math:`A C` is ``A`` in the metric of :math:`M^{-1}` in which
the generalized inverse forms :math:`A M^{-1} A^T` (paper eq 5), made free of units.

The eigenvalues' own scale is :math:`\operatorname{tr} K / \operatorname{tr} M`
(:func:`stiffness_over_mass`), and a rigid-body mode's round-off eigenvalue is below a fixed
fraction of it (:func:`rigid_eigenvalue`), whatever the units.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence, TypeVar

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = [
    "Equilibrated",
    "RowScale",
    "ZeroRowError",
    "equilibrate",
    "mass_column_scale",
    "definite_mass",
    "massless_coordinates",
    "RIGID_ENERGY_TOL",
    "rigid_eigenvalue",
    "rigid_modes",
    "row_scale",
    "spectral_norm",
    "stiffness_over_mass",
]

MatrixT = TypeVar("MatrixT", np.ndarray, sp.csr_array)


class ZeroRowError(ValueError):
    """A constraint row with no nonzero entry (its terms cancel): it constrains nothing.

    Attributes:
        rows: indices of the empty rows.
    """

    def __init__(self, rows: Sequence[int], labels: Sequence[str] | None = None) -> None:
        self.rows = [int(i) for i in rows]
        names = [repr(labels[i]) if labels is not None else f"row {i}" for i in self.rows]
        super().__init__(f"constraint {names[0]} is an empty row of A (its terms cancel, or "
                         f"every point it names is supported): it constrains nothing"
                         + (f"; {len(names) - 1} more such row(s)" if len(names) > 1 else ""))


@dataclass(frozen=True)
class RowScale:
    r"""The row factors of an equilibration, powers of two: :math:`d_i = 2^{-e_i}`,

    .. math::  e_i = \operatorname{round} \log_2 (s_i \nu_i), \qquad
               2^{-1/2} \le \| d_i a_i \|_2 \le 2^{1/2},

    so that scaling rounds nothing (LAPACK's ``xGEEQUB`` scales by powers of the radix for the
    same reason: a row ``[1, -1]`` is not turned into ``[0.7071..., -0.7071...]``, and an
    ill-conditioned root that depends on its last bits is left as it was), and no factor
    over- or underflows (:math:`s_i = 10^{-300}` gives :math:`e_i = -997`).

    Attributes:
        exponent: :math:`e_i` for each row (``0`` for a zero row kept as it is).
        norms: the 2-norms :math:`s_i \nu_i` of the rows (``0`` for a zero row).
    """

    exponent: np.ndarray
    norms: np.ndarray

    def apply(self, X: MatrixT) -> MatrixT:
        r"""``D X``: row ``i`` of ``X`` (a vector, an array or a sparse matrix with as many rows
        as ``A``) multiplied by :math:`2^{-e_i}`, exactly."""
        if sp.issparse(X):
            Xc = sp.csr_array(X, copy=True)
            counts = np.diff(Xc.indptr)
            Xc.data = _ldexp(Xc.data, -np.repeat(self.exponent, counts))
            return Xc
        Xd = np.asarray(X)
        shape = (-1,) + (1,) * (Xd.ndim - 1)
        return _ldexp(Xd, -self.exponent.reshape(shape))

    def ratio(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        r""":math:`d_j / d_i = 2^{e_i - e_j}` for ``i`` in ``rows`` (down) and ``j`` in ``cols``
        (across): turns a combination of scaled rows into one of the rows themselves."""
        return np.ldexp(1.0, self.exponent[rows, None] - self.exponent[None, cols])


def _ldexp(X: np.ndarray, e: np.ndarray) -> np.ndarray:
    """``X * 2**e`` for real or complex ``X`` (exact unless the result leaves the range)."""
    if np.iscomplexobj(X):
        return np.ldexp(X.real, e) + 1j * np.ldexp(X.imag, e)
    return np.ldexp(np.asarray(X, dtype=float), e)


def row_scale(A: sp.sparray | sp.spmatrix | np.ndarray,
              labels: Sequence[str] | None = None, *, keep_zero: bool = False) -> RowScale:
    r"""The equilibrating row factors of ``A`` (see the module docstring and :class:`RowScale`).

    .. math::  s_i = \max_j |a_{ij}|, \qquad \nu_i = \| a_i / s_i \|_2, \qquad
               e_i = \operatorname{round} (\log_2 s_i + \log_2 \nu_i)

    Args:
        A: ``m x n`` constraint matrix, dense or sparse.
        labels: row names for the error message.
        keep_zero: give a zero row the factor 1 instead of refusing it (for the rank of a
            block of columns, whose zero rows are legitimate; a whole constraint row that is
            zero is refused at the entry of every analysis).

    Raises:
        ZeroRowError: a row with no nonzero entry (unless ``keep_zero``).
    """
    if sp.issparse(A):
        Ac = sp.csr_array(A, dtype=float)
        m = Ac.shape[0]
        counts = np.diff(Ac.indptr)
        rows = np.repeat(np.arange(m), counts)
        s = np.zeros(m)
        np.maximum.at(s, rows, np.abs(Ac.data))
        zero = _refuse_zero(s, labels, keep_zero)
        s = np.where(zero, 1.0, s)
        nu2 = np.zeros(m)
        np.add.at(nu2, rows, (Ac.data / s[rows]) ** 2)
    else:
        Ad = np.asarray(A, dtype=float).reshape(np.shape(A)[0], -1)
        s = np.abs(Ad).max(axis=1, initial=0.0)
        zero = _refuse_zero(s, labels, keep_zero)
        s = np.where(zero, 1.0, s)
        nu2 = np.sum((Ad / s[:, None]) ** 2, axis=1)
    if not np.all(np.isfinite(s)):
        raise ValueError("constraint matrix with an infinite or NaN entry")
    nu = np.sqrt(np.where(zero, 1.0, nu2))
    exponent = np.where(zero, 0, np.round(np.log2(s) + np.log2(nu))).astype(np.int64)
    return RowScale(exponent=exponent, norms=np.where(zero, 0.0, s * nu))


def _refuse_zero(s: np.ndarray, labels: Sequence[str] | None, keep_zero: bool) -> np.ndarray:
    """The mask of the zero rows (largest magnitude ``s == 0``), refused unless ``keep_zero``."""
    zero = s == 0
    if zero.any() and not keep_zero:
        raise ZeroRowError(np.flatnonzero(zero).tolist(), labels)
    return zero


@dataclass(frozen=True)
class Equilibrated:
    r"""Constraints ``A q = b + R F`` with every row scaled to unit 2-norm: ``D A``, ``D b``,
    ``D R`` (the same solutions).

    Attributes:
        A: ``D A`` (dense if ``A`` was dense, else sparse CSR).
        b: ``D b`` or ``None``.
        R: ``D R`` or ``None``.
        scale: the factors :math:`D` (:class:`RowScale`).
    """

    A: np.ndarray | sp.csr_array
    b: np.ndarray | None
    R: np.ndarray | sp.csr_array | None
    scale: RowScale


def equilibrate(A: sp.sparray | sp.spmatrix | np.ndarray,
                b: np.ndarray | None = None,
                R: sp.sparray | sp.spmatrix | np.ndarray | None = None, *,
                labels: Sequence[str] | None = None) -> Equilibrated:
    r"""Scale the rows of ``A q = b + R F`` together to unit 2-norm.

    .. math::  D A q = D b + D R F, \qquad \| (D A)_i \|_2 = 1

    Args:
        A: ``m x n`` constraint matrix (dense or sparse).
        b: ``m`` right-hand sides, or ``None``.
        R: ``m x k`` force ties (eq 14), or ``None``.
        labels: row names for the error message.

    Raises:
        ZeroRowError: a row of ``A`` with no nonzero entry.
    """
    scale = row_scale(A, labels)
    As = scale.apply(sp.csr_array(A, dtype=float) if sp.issparse(A) else np.asarray(A, float))
    bs = None if b is None else scale.apply(np.asarray(b, dtype=float))
    Rs = None
    if R is not None:
        Rs = scale.apply(sp.csr_array(R) if sp.issparse(R) else np.asarray(R))
    return Equilibrated(A=As, b=bs, R=Rs, scale=scale)


def massless_coordinates(M: sp.sparray | sp.spmatrix | np.ndarray) -> np.ndarray:
    """Boolean mask of the coordinates with no mass: the zero rows of ``M`` (paper eq 6)."""
    if sp.issparse(M):
        return np.asarray(abs(sp.csr_array(M)).sum(axis=1)).ravel() == 0.0
    return np.abs(np.asarray(M)).sum(axis=1) == 0.0


def mass_column_scale(M: sp.sparray | sp.spmatrix | np.ndarray) -> np.ndarray:
    r"""Column factors :math:`c_j = (\bar m / m_{jj})^{1/2}` that make coordinates of different
    mass (units) comparable: :math:`A C` is ``A`` in the metric of :math:`M^{-1}`, normalized so
    that a model of uniform mass has :math:`C = I`.

    :math:`\bar m` is the mean diagonal mass of the coordinates that have mass; a massless
    coordinate takes :math:`\bar m`, as it does in :math:`M_d` of the paper's eq (7).
    """
    d = np.abs(M.diagonal() if sp.issparse(M) else np.diag(np.asarray(M))).astype(float)
    pos = (d > 0) & ~massless_coordinates(M)
    mean = float(np.mean(d[pos])) if pos.any() else 1.0
    return np.sqrt(mean / np.where(pos, d, mean))


def spectral_norm(A: sp.sparray | sp.spmatrix | np.ndarray) -> float:
    r"""The spectral norm :math:`\|A\|_2 = \sqrt{\lambda_{max}(A A^T)}` (``1`` for an empty or zero
    ``A``, so that it can divide a residual).  Dense eigenvalues up to 400 rows, else Lanczos to
    ``1e-4``."""
    As = sp.csr_array(A, dtype=float)
    m = As.shape[0]
    if m == 0:
        return 1.0
    AAt = sp.csr_array(As @ As.T)
    if m <= 400:
        return float(np.sqrt(max(np.linalg.eigvalsh(AAt.toarray()).max(), 0.0))) or 1.0
    lam = spla.eigsh(AAt, k=1, which="LA", tol=1e-4, return_eigenvectors=False)[0]
    return float(np.sqrt(max(lam, 0.0))) or 1.0


def definite_mass(K: sp.sparray | sp.spmatrix, M: sp.sparray | sp.spmatrix) -> sp.csr_array:
    r""":math:`M_d` of the paper's eq (6): ``M`` with a mass put on each massless coordinate,

    .. math::  (M_d)_{ii} = c\, K_{ii}, \qquad
               c = \operatorname{median}_{j:\, m_{jj} > 0,\, k_{jj} > 0} \frac{m_{jj}}{k_{jj}},

    a mass in the units of the coordinate (a change of units :math:`u = S u'` turns ``K, M`` into
    ``S K S, S M S`` and the filled mass into :math:`S M_d S`, so nothing computed with
    :math:`M_d` depends on the units).  A massless coordinate with no stiffness either takes the
    mean diagonal mass of the others (and 1 if there is none).  ``M`` with no massless
    coordinate is returned as it is.
    """
    Mc = sp.csr_array(M, dtype=float)
    massless = massless_coordinates(Mc)
    if not massless.any():
        return Mc
    k = np.abs(sp.csr_array(K).diagonal())
    m = np.abs(Mc.diagonal())
    both = (m > 0) & (k > 0) & ~massless
    c = float(np.median(m[both] / k[both])) if both.any() else 0.0
    mean = float(np.mean(m[~massless])) if (~massless).any() else 1.0
    fill = np.where(massless, np.where(k > 0, c * k, 0.0), 0.0)
    fill = np.where(massless & (fill <= 0), mean or 1.0, fill)
    return sp.csr_array(Mc + sp.diags_array(fill))


def stiffness_over_mass(K: sp.sparray, M: sp.sparray) -> float:
    r""":math:`\operatorname{tr} K / \operatorname{tr} M`, the scale of the eigenvalues."""
    return max(abs(K.diagonal()).sum() / max(abs(M.diagonal()).sum(), 1e-300), 1e-300)


def rigid_eigenvalue(K: sp.sparray, M: sp.sparray) -> float:
    r"""The largest :math:`|\omega^2|` read as a rigid-body mode,
    :math:`10^{-12} \operatorname{tr} K / \operatorname{tr} M`: round-off of the size
    :math:`\epsilon |K| / |M|` (a free-free rod of 600 coordinates gave :math:`\omega` =
    1e-5 rad/s)."""
    return 1e-12 * stiffness_over_mass(K, M)


#: A motion is rigid when its strain energy ``u^T K u`` is below this fraction of
#: ``|u|^T |K| |u|``, the level at which ``K u`` is rounded (rigid-body modes computed by
#: shift-invert Lanczos: below ``1e-17``; a ``1e12`` spring in series with a ``1`` leaves
#: ``2.5e-13``; a steel box of 1 mm elements on springs of 1 N/m, its suspension modes at 6 to
#: 9 rad/s: ``2.6e-13`` and more).
RIGID_ENERGY_TOL = 3e-14


def rigid_modes(lam: np.ndarray, U: np.ndarray, K: sp.sparray, M: sp.sparray) -> np.ndarray:
    r"""Which eigenpairs :math:`(\lambda_j, u_j)` of ``K u = lambda M u`` are rigid-body modes.

    A pair with :math:`|\lambda_j| \le` :func:`rigid_eigenvalue` is rigid when
    :math:`\lambda_j < 0` (no stiffness gives it), or when its eigenvalue is round-off of the
    stiffness's scale, :math:`\lambda_j \le 64 \epsilon \operatorname{tr} K /
    \operatorname{tr} M` (a motion of coordinates that no stiffness reaches, whose
    :math:`|u|^T |K| |u|` is only the vector's own error), or when its strain energy is
    round-off componentwise,

    .. math::  u_j^T K u_j \le \tau\, |u_j|^T |K|\, |u_j|, \qquad
               \tau = \text{RIGID\_ENERGY\_TOL}.

    Neither test depends on the units, and neither reads a soft mode beside a stiff part as
    rigid: the suspension modes of a stiff body on soft springs can have :math:`\omega^2`
    below :math:`10^{-12} \operatorname{tr} K / \operatorname{tr} M` and are kept with their
    frequency (as the dense path's rigid basis keeps them).

    Returns:
        a boolean mask over the columns of ``U``.
    """
    lam = np.asarray(lam, dtype=float)
    rigid = np.abs(lam) <= rigid_eigenvalue(K, M)
    check = np.flatnonzero(rigid & (lam > 64 * np.finfo(float).eps * stiffness_over_mass(K, M)))
    if check.size:
        Uc = np.asarray(U[:, check], dtype=float)
        Kc = sp.csr_array(K)
        energy = np.einsum("ij,ij->j", Uc, Kc @ Uc)
        level = np.einsum("ij,ij->j", np.abs(Uc), abs(Kc) @ np.abs(Uc))
        rigid[check] = energy <= RIGID_ENERGY_TOL * level
    return rigid
