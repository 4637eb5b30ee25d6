r"""Property-based cross-checks of the coupler (issue 6, item 4; DESIGN.md section 4, rungs 3, 5).

Random systems, drawn by hypothesis, are solved by the three formulations, which must agree:

* receptances (eq 15, null space, KKT) to ``1e-9`` relative, constraint residual
  ``|A H - R| <= 1e-10 |A| |H|``, reciprocity ``H = H^T`` for homogeneous constraints;
* coupled modes (eqs 30-34, null space, KKT): the same number of physical modes, eigenvalues to
  ``1e-9`` relative, mode residuals ``|A u| / (|A| |u|) < 1e-10``, and ``2 rank(A)`` zero roots
  set aside by the paper's pencil;
* Cauchy interlacing of the undamped frequencies when one constraint is added;
* the constrained acceleration of eq (5) / eq (10) equals the Lagrange-multiplier acceleration.

What is drawn:

* ``M`` symmetric positive definite, or semidefinite with massless coordinates that the
  constraints reach (a massless coordinate gets a large entry in one row of ``A``); for the
  modes also massless coordinates that no constraint reaches (then ``K`` is definite on them);
* ``K`` definite, or semidefinite with a null space of dimension 1 or 2 (rigid-body motions,
  some of which the constraints may leave free);
* ``C`` zero, proportional (``a M + b K``) or non-proportional (``Z Z^T`` of random rank), from
  light to heavy (over-damped roots appear);
* ``A`` with ``m`` independent random rows plus 0-2 redundant rows (combinations of the others),
  and ``R`` zero (homogeneous) or random with redundant rows consistent.

Conditioning, which makes the tolerances meaningful.  Each of ``M`` and ``K`` has its nonzero
eigenvalues within a factor of 1000 (``s 10^-1.5 .. s 10^1.5``), and the unit scales ``s`` of
``M`` and of ``K`` are drawn independently in ``1e-3 .. 1e3``: units change by six decades, the
condition numbers stay at most ``1e3``.  Relative accuracy of a backward-stable solver is about
``eps cond``; measured with eigenvalues spread over ``1e-3 .. 1e3`` (condition ``1e6`` each):
the acceleration of eq (5) and the KKT one differ by up to ``3e-6``, the receptances by
``2e-9``, mode residuals reach ``3e-10`` (the eigenvalues, refined on their Rayleigh
functionals, still agree to ``2e-11``).  There ``1e-9`` would test LAPACK, not this program.
For the modes one more condition is imposed (``assume``, about 2% of the draws): every
nonzero physical root is at least ``1e-4`` of the largest.  Near-mechanisms (a semidefinite
``K`` whose null space the constraints cut at a small angle) and slow decays (weakly damped
rigid-body motions) break it: such a root sits next to the zero roots, where the roots of every
formulation are ill conditioned and those of the paper's pencil (34) worse, next to its
``2 rank(A)`` defective spurious zeros; the Rayleigh refinement (``substruct.analysis.modes.pencil``) recovers
most of it, ``tests/test_awkward_models.py`` shows the size of the effect.

Examples are drawn with ``derandomize=True`` and no example database: the same code gives the
same examples on every run, so CI is reproducible.  (Hypothesis also mixes in numeric constants
that it finds in the project's loaded modules, so the examples of the whole suite differ from
those of this file alone, and change when the code does; a failure prints its
``@reproduce_failure`` blob.)  Set ``SUBSTRUCT_HYPOTHESIS_EXAMPLES`` to a factor (e.g. 10) to
scale the numbers up for a long search.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from substruct.linalg.constraints import independent_rows
from substruct.analysis.formulations.coupling import (FORMULATIONS, constrained_acceleration, receptance,
                                receptance_agreement)
from substruct.analysis.checks import modes_agreement
from substruct.analysis.modes.dense import FORMULATIONS, coupled_modes

#: log10 of the half-width of each matrix's eigenvalue band (a condition number of 1e3)
HALF_DECADES = 1.5
#: every nonzero physical root is at least this fraction of the largest (``assume``)
SPREAD = 1e-4
FACTOR = float(os.environ.get("SUBSTRUCT_HYPOTHESIS_EXAMPLES", "1"))
#: examples per property; 1150 in all
EXAMPLES = {"receptance": 350, "modes": 400, "interlacing": 200, "acceleration": 200}


def _settings(name: str):
    return settings(max_examples=int(EXAMPLES[name] * FACTOR), deadline=None, derandomize=True,
                    database=None, print_blob=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


# --------------------------------------------------------------------------------------------
# strategies


@dataclass
class System:
    """A drawn system; ``describe()`` is printed when a property fails."""

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    A: np.ndarray
    R: np.ndarray | None
    massless: np.ndarray
    info: dict

    def describe(self) -> str:
        return f"{self.info}"


def _spd(rng: np.random.Generator, n: int, scale: float, defect: int = 0) -> np.ndarray:
    """``Q diag(ev) Q^T``, ``ev`` log-uniform in ``scale * 10^[-1.5, 1.5]``, ``defect`` zeros."""
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    ev = scale * 10 ** rng.uniform(-HALF_DECADES, HALF_DECADES, n)
    ev[n - defect:] = 0.0
    S = (Q * ev) @ Q.T
    return (S + S.T) / 2


@st.composite
def systems(draw, *, massless: str = "reached", rhs: bool = True, damping: bool = True,
            psd_k: bool = True, min_constraints: int = 1, redundant: bool = True) -> System:
    """A random constrained system (see the module docstring).

    Args:
        massless: ``"none"``, ``"reached"`` (every massless coordinate is in some row of ``A``)
            or ``"any"`` (massless coordinates may be left free; ``K`` is then definite).
        rhs: draw a nonhomogeneous ``R`` half of the time.
        damping: draw ``C`` (else zero).
        psd_k: allow a semidefinite ``K``.
        min_constraints: least number of independent rows of ``A``.
        redundant: allow redundant rows.
    """
    n = draw(st.integers(2, 8), label="n")
    m = draw(st.integers(min(min_constraints, n - 1), n - 1), label="m")
    seed = draw(st.integers(0, 2**32 - 1), label="seed")
    rng = np.random.default_rng(seed)
    n_red = draw(st.integers(0, 2), label="redundant rows") if redundant and m else 0
    kind_m = draw(st.sampled_from(["none"] if massless == "none" or m == 0 else
                                  ["none", "massless"]), label="mass")
    reach = massless == "reached" or draw(st.booleans(), label="constraints reach massless")
    n_ml = draw(st.integers(1, min(2, m if reach else n - 1)), label="massless") \
        if kind_m == "massless" else 0
    defect = draw(st.integers(0, min(2, n - 1)), label="K defect") \
        if psd_k and (reach or n_ml == 0) else 0
    kind_c = draw(st.sampled_from(["zero", "proportional", "non-proportional"]),
                  label="damping") if damping else "zero"
    level = 10 ** draw(st.floats(-3.0, 0.3), label="log10 damping level")
    mexp = draw(st.floats(-3.0, 3.0), label="log10 mass scale")
    kexp = draw(st.floats(-3.0, 3.0), label="log10 stiffness scale")
    nonhom = rhs and m and draw(st.booleans(), label="nonhomogeneous")

    M = _spd(rng, n, 10**mexp)
    K = _spd(rng, n, 10**kexp, defect)
    ml = np.sort(rng.choice(n, n_ml, replace=False)) if n_ml else np.zeros(0, int)
    M[ml, :] = 0.0
    M[:, ml] = 0.0
    wref = np.sqrt(10 ** (kexp - mexp))
    if kind_c == "zero":
        C = np.zeros((n, n))
    elif kind_c == "proportional":
        a, b = rng.uniform(0, 1, 2)
        C = 2 * level * (a * wref * M + b * K / wref)
    else:
        kz = int(rng.integers(1, n + 1))
        Z = rng.standard_normal((n, kz))
        C = 2 * level * wref * 10**mexp * (Z @ Z.T) / kz
    A = rng.standard_normal((m, n))
    if reach:
        for j, col in enumerate(ml):
            A[j % m, col] += 3.0 * rng.choice([-1.0, 1.0])
    R = rng.standard_normal((m, n)) if nonhom else None
    if n_red:
        W = rng.standard_normal((n_red, m))
        A = np.vstack([A, W @ A])
        R = None if R is None else np.vstack([R, W @ R])
        perm = rng.permutation(m + n_red)
        A = A[perm]
        R = None if R is None else R[perm]
    info = dict(n=n, m=m, redundant=n_red, massless=ml.tolist(), reach=reach, K_defect=defect,
                damping=kind_c, level=level, mass_scale=10**mexp, stiffness_scale=10**kexp,
                nonhomogeneous=bool(nonhom), seed=seed)
    return System(M, C, K, A, R, ml, info)


def _root_tolerance(md, floor: float = 1e-9) -> float:
    """The largest relative difference of :func:`modes_agreement` that rounding explains:
    ``floor``, or the first-order sensitivity of the worst root, ``c eps s^2 / (sep_j |l_j|)``,
    where ``s`` is the largest root and ``sep_j`` the distance of root ``j`` to its nearest
    neighbour (a zero root and the conjugate included): a root next to another one (a slowly
    decaying rigid-body motion beside its zero root) moves by ``eps s^2 / sep`` under a
    perturbation ``eps s`` of the pencil, ``c = 10 n`` its constant.  Zero roots are exact in
    every formulation (rigid-body motions found from the null space of ``[K; A]``) and held to
    ``floor``."""
    lam = np.asarray(md.eigenvalues, dtype=complex)
    if lam.size < 1:
        return floor
    s = max(float(np.abs(lam).max()), 1e-300)
    roots = np.concatenate([lam, lam.conj(), [0.0]])
    worst = floor
    for lj in lam[lam != 0]:
        d = np.abs(roots - lj)
        d = d[d > 1e-14 * s]
        sep = float(d.min()) if d.size else s
        denom = max(abs(lj), 1e-8 * s)
        worst = max(worst, 10 * lam.size * np.finfo(float).eps * s * s / (sep * denom))
    return worst


def _spread_ok(md, ratio: float = SPREAD) -> bool:
    """Every nonzero root at least ``ratio`` of the largest (see the module docstring)."""
    mag = np.abs(md.eigenvalues)
    mag = mag[mag > 0]
    return not mag.size or mag.min() >= ratio * mag.max()


# --------------------------------------------------------------------------------------------
# receptances (eqs 11-15)


@_settings("receptance")
@given(sys_=systems(massless="reached"), fractions=st.lists(st.floats(0.05, 3.0), min_size=1,
                                                           max_size=3, unique=True))
def test_receptance_formulations_agree(sys_, fractions):
    M, C, K, A, R = sys_.M, sys_.C, sys_.K, sys_.A, sys_.R
    wref = np.sqrt(np.linalg.norm(K) / np.linalg.norm(M))
    omegas = np.sort(fractions) * wref
    agree = receptance_agreement(K, M, C, A, omegas, R)
    assert max(agree.values()) < 1e-9, (agree, sys_.describe())
    for method in FORMULATIONS:
        H = receptance(K, M, C, A, omegas, R, method=method)
        scale = np.abs(H).max()
        target = 0.0 if R is None else R
        res = np.abs(np.einsum("ij,wjk->wik", A, H) - target).max()
        assert res <= 1e-10 * np.abs(A).max() * scale, (method, res, sys_.describe())
        if R is None:
            asym = np.abs(H - H.transpose(0, 2, 1)).max()
            assert asym <= 1e-10 * scale, (method, asym, sys_.describe())


# --------------------------------------------------------------------------------------------
# coupled modes (eqs 23-34)


@_settings("modes")
@given(sys_=systems(massless="any", rhs=False, min_constraints=0))
def test_modes_formulations_agree(sys_):
    M, C, K, A = sys_.M, sys_.C, sys_.K, sys_.A
    sets = {mth: coupled_modes(M, C, K, A, method=mth) for mth in FORMULATIONS}
    ref = sets["null-space"]
    assume(_spread_ok(ref))
    rank = independent_rows(A).rank if A.size else 0
    for mth, md in sets.items():
        assert len(md) == len(ref), (mth, md.eigenvalues, ref.eigenvalues, sys_.describe())
        gap = modes_agreement(md, ref)
        assert gap < _root_tolerance(ref), (mth, gap, _root_tolerance(ref), sys_.describe())
        assert np.all(md.residual < 1e-10), (mth, md.residual.max(), sys_.describe())
        assert np.all(md.eigenvalues.imag >= 0)
        assert np.all(md.eigenvalues.real <= 1e-9 * np.abs(md.eigenvalues).max(initial=1.0))
        assert len(md.spurious) == len(md.spurious_reason)
    # the paper's pencil sets aside 2 rank(A) zero roots and, with the other two, the same
    # number of roots in all (2 n)
    gi = sets["generalized-inverse"]
    n_zero = sum("violates A u = 0" in r for r in gi.spurious_reason)
    assert n_zero == 2 * rank, (gi.spurious, sys_.describe())
    # every root is accounted for: the pencils have 2n, 2(n - rank) and 2(n + rank) roots, and
    # what each sets aside leaves the same number of physical roots
    n = K.shape[0]
    size = {"generalized-inverse": 2 * n, "null-space": 2 * (n - rank), "kkt": 2 * (n + rank)}
    physical = {mth: size[mth] - len(md.spurious) for mth, md in sets.items()}
    assert len(set(physical.values())) == 1, (physical, sys_.describe())


@_settings("interlacing")
@given(sys_=systems(massless="none", rhs=False, damping=False, min_constraints=0),
       extra=st.sampled_from(["random", "redundant"]), extra_seed=st.integers(0, 2**32 - 1))
def test_adding_a_constraint_interlaces(sys_, extra, extra_seed):
    """Cauchy interlacing: ``w_i <= w'_i <= w_(i+1)`` for the undamped frequencies without
    (``w``) and with (``w'``) one more constraint; a redundant one changes nothing."""
    M, K, A = sys_.M, sys_.K, sys_.A
    n = K.shape[0]
    rng = np.random.default_rng(extra_seed)
    if extra == "random" or not A.shape[0]:
        row = rng.standard_normal((1, n))
    else:
        row = rng.standard_normal((1, A.shape[0])) @ A
    A1 = np.vstack([A, row])
    added = independent_rows(A1).rank - (independent_rows(A).rank if A.size else 0)
    for method in FORMULATIONS:
        w0 = coupled_modes(M, None, K, A, method=method).omega
        w1 = coupled_modes(M, None, K, A1, method=method).omega
        assert w1.size == w0.size - added, (method, w0, w1, sys_.describe())
        tol = 1e-9 * w0.max()
        if added:
            assert np.all(w0[:-1] <= w1 + tol) and np.all(w1 <= w0[1:] + tol), \
                (method, w0, w1, sys_.describe())
        else:
            np.testing.assert_allclose(w1, w0, rtol=1e-9, atol=tol)


# --------------------------------------------------------------------------------------------
# constrained acceleration (eqs 5, 10)


@_settings("acceleration")
@given(sys_=systems(massless="reached", rhs=False, damping=False),
       vec_seed=st.integers(0, 2**32 - 1))
def test_acceleration_eq5_equals_lagrange(sys_, vec_seed):
    r"""``q'' = a + M^{-1} A^T (A M^{-1} A^T)^+ (b - A a)`` (eq 5, eq 10 with massless
    coordinates) equals the solution of ``[M, A^T; A, 0] [q''; -f_c] = [force; b]``."""
    M, A = sys_.M, sys_.A
    n = M.shape[0]
    rng = np.random.default_rng(vec_seed)
    b = A @ rng.standard_normal(n)                   # consistent, redundant rows included
    force = rng.standard_normal(n) * np.abs(M).max()
    qdd = constrained_acceleration(sp.csr_array(M), A, b, force)
    rows = independent_rows(A)
    Ak = A[rows.keep]
    kkt = np.block([[M, Ak.T], [Ak, np.zeros((rows.rank, rows.rank))]])
    ref = np.linalg.solve(kkt, np.concatenate([force, b[rows.keep]]))[:n]
    scale = np.abs(ref).max()
    assert np.abs(qdd - ref).max() <= 1e-9 * scale, (np.abs(qdd - ref).max(), sys_.describe())
    res = np.abs(A @ qdd - b).max()
    assert res <= 1e-10 * np.abs(A).max() * scale, (res, sys_.describe())
