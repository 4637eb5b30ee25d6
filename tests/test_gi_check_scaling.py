"""The residual checks of the production path do not depend on the units of the coordinates:
a clamped plate of DKQ shells in two frames tied in all six components (rotary inertia 1e-5 of
the mass per area, drilling stiffness a small penalty) passes them at the default tolerance, a
change of the rotations' units leaves their figures and the frequencies as they were, and a
wrong frequency, a wrong shape or a wrong constraint row still fails them."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.analysis.api import modes
from substruct.analysis.modes.checks import generalized_inverse_residual, kkt_residual
from substruct.analysis.modes.krylov import check_inputs, eliminate
from substruct.analysis.modes.production import GI_CHECK, KKT_CHECK, production_modes
from substruct.assembly.stack import Connection, PointRef, assemble
from substruct.case.analysis import DEFAULT_TOLERANCE
from substruct.linalg.scaling import definite_mass
from substruct.models.beam import Material
from substruct.models.frame import frame
from substruct.models.shell_mesh import Shell

E, G, RHO, T = 2.1e11, 8.1e10, 7850.0, 0.01
N = 10  # elements along each side of a half: 1,386 coordinates
COUNT = 20


def _edges(n: int) -> tuple[list[int], list[int]]:
    inner = list(range(1, n))
    return [1] + [10 + j for j in inner] + [4], [2] + [10 + n + j for j in inner] + [3]


def _half(name: str, x0: float, width: float, nx: int, n: int, clamped: list[int]):
    a, b = _edges(n)
    nodes = {1: [x0, 0.0, 0.0], 2: [x0 + width, 0.0, 0.0], 3: [x0 + width, 1.0, 0.0],
             4: [x0, 1.0, 0.0]}
    for j in range(1, n):
        nodes[a[j]] = [x0, j / n, 0.0]
        nodes[b[j]] = [x0 + width, j / n, 0.0]
    return frame(name, nodes, [], supports={i: "123456" for i in clamped},
                 shells=[Shell((1, 2, 3, 4), T, Material(E=E, G=G, rho=RHO), (nx, n))])


def _ties(n: int, shift: int = 0) -> list[Connection]:
    """Left's ``x = 1`` edge tied to right's ``x = 1`` edge in six components; ``shift`` moves
    the ``uz`` tie of the middle node one node along the edge (a wrong row)."""
    edge0, edge1 = _edges(n)
    out = []
    for k, (a, b) in enumerate(zip(edge1, edge0)):
        for c in ("ux", "uy", "uz", "rx", "ry", "rz"):
            bb = edge0[k + shift] if (c == "uz" and k == n // 2) else b
            out.append(Connection(PointRef("left", f"{a}:{c}"), PointRef("right", f"{bb}:{c}")))
    return out


@pytest.fixture(scope="module")
def plate():
    subs = [_half("left", 0.0, 1.0, N, N, _edges(N)[0]), _half("right", 1.0, 1.0, N, N, [])]
    return subs, assemble(subs, _ties(N))


def _prepared(asm):
    Ms, Ks, As, _ = check_inputs(asm.M, asm.K, asm.A, COUNT)
    el = eliminate(Ms, As)
    return Ks, Ms, sp.csr_array(As[el.kept_rows])


def test_shell_plate_passes_the_checks_at_the_default_tolerance(plate):
    _, asm = plate
    res = modes(asm.M, None, asm.K, asm.A, COUNT, solver="sparse")  # raises past 1e-6
    assert set(res.agreement) == {KKT_CHECK, GI_CHECK}
    assert max(res.agreement.values()) < 1e-2 * DEFAULT_TOLERANCE
    # the whole plate, the seam nodes shared, by shift-invert Lanczos (a dense eigh is off by
    # 1.8e-8 on the first mode: its error eps omega_max^2 / omega_1^2 is 2e-7 here); the gross
    # mass-norm residual of the modes, 1.0e-9 (net of round-off 2e-13), bounds the relative
    # error of omega^2 by twice itself (measured: 1.7e-11 in omega)
    whole = _half("plate", 0.0, 2.0, 2 * N, N, _edges(N)[0])
    sigma = -1e-9 * whole.K.diagonal().sum() / whole.M.diagonal().sum()
    lam = spla.eigsh(sp.csc_array(whole.K), k=COUNT, M=sp.csc_array(whole.M), sigma=sigma,
                     return_eigenvectors=False, tol=0, v0=np.ones(whole.K.shape[0]))
    ref = np.sqrt(np.sort(lam))
    assert np.max(np.abs(res.omega / ref - 1)) < 1e-9


def test_wrong_modes_fail_the_checks(plate):
    subs, asm = plate
    Ks, Ms, Ak = _prepared(asm)
    good, _, _ = production_modes(asm.M, asm.K, asm.A, COUNT)
    U, w = good.shapes.real, good.omega
    # a frequency off by 1e-5 relative (2e-5 in omega^2): the mass-norm figure bounds it
    off = w.copy()
    off[3] *= 1.0 + 1e-5
    assert 5e-6 < generalized_inverse_residual(Ks, Ms, Ak, 1j * off, U) < 2e-5
    assert 5e-6 < kkt_residual(Ks, Ms, Ak, 1j * off, U) < 2e-5
    # a shape with 1e-4 of the next mode in it
    mixed = U.copy()
    mixed[:, 0] += 1e-4 * U[:, 1]
    assert generalized_inverse_residual(Ks, Ms, Ak, 1j * w, mixed) > 10 * DEFAULT_TOLERANCE
    assert kkt_residual(Ks, Ms, Ak, 1j * w, mixed) > 10 * DEFAULT_TOLERANCE
    # every entry of the shapes rounded again (1 eps): round-off, read as nothing; every entry
    # off by 1e-9 relative: far above it (a few hundred times the tolerance)
    rng = np.random.default_rng(7)
    for rel, passes in ((np.finfo(float).eps, True), (1e-9, False)):
        noisy = U * (1.0 + rel * rng.standard_normal(U.shape))
        for check in (generalized_inverse_residual, kkt_residual):
            figure = check(Ks, Ms, Ak, 1j * w, noisy)
            assert (figure < 1e-3 * DEFAULT_TOLERANCE) if passes else \
                (figure > 10 * DEFAULT_TOLERANCE)
    # modes of a model whose uz tie at the middle of the seam names the wrong node
    wrong = assemble(subs, _ties(N, shift=1))
    bad, _, _ = production_modes(wrong.M, wrong.K, wrong.A, COUNT)
    assert generalized_inverse_residual(Ks, Ms, Ak, bad.eigenvalues, bad.shapes) > 1e-3
    assert kkt_residual(Ks, Ms, Ak, bad.eigenvalues, bad.shapes) > 1e-3


def _units(asm, factor: float) -> sp.dia_array:
    """``S``: the rotations' coordinates in units ``factor`` times larger (``u = S u'``)."""
    rot = np.array([lab.split(":")[-1].startswith("r") for lab in asm.dof_labels])
    assert rot.sum() == asm.n_dof // 2
    return sp.diags_array(np.where(rot, 1.0 / factor, 1.0))


@pytest.mark.parametrize("factor", [1e3, 1e-3])
def test_a_change_of_the_rotations_units_changes_no_figure(plate, factor):
    _, asm = plate
    S = _units(asm, factor)
    Ks, Ms, Ak = _prepared(asm)
    Kt, Mt, At = sp.csr_array(S @ Ks @ S), sp.csr_array(S @ Ms @ S), sp.csr_array(Ak @ S)
    good, agreement, _ = production_modes(asm.M, asm.K, asm.A, COUNT)
    U, w = good.shapes.real, good.omega
    Ut = U / S.diagonal()[:, None]
    # a planted error far above round-off (a frequency 1e-6 off, 1e-7 of another mode mixed
    # in) measured in both units: the same figures to 1e-4 of themselves
    off = w * (1.0 + 1e-6 * np.arange(COUNT) / COUNT)
    mix = U + 1e-7 * np.roll(U, 1, axis=1)
    mixt = mix / S.diagonal()[:, None]
    for check in (generalized_inverse_residual, kkt_residual):
        for shapes, shapes_t in ((U, Ut), (mix, mixt)):
            a = check(Ks, Ms, Ak, 1j * off, shapes)
            b = check(Kt, Mt, At, 1j * off, shapes_t)
            assert a > 1e-7 and abs(b / a - 1) < 1e-4
    # the Euclidean size of the residual is not unit-free: the transformation is no identity
    r = (Ks @ U[:, :1] - w[0] ** 2 * (Ms @ U[:, :1]))
    rt = (Kt @ Ut[:, :1] - w[0] ** 2 * (Mt @ Ut[:, :1]))
    assert abs(np.linalg.norm(rt) / np.linalg.norm(r) - 1) > 0.1 or \
        abs(np.linalg.norm(Ut[:, 0]) / np.linalg.norm(U[:, 0]) - 1) > 0.1
    # the production path on the model in the other units: same frequencies, both figures
    # (net of round-off) far below the default tolerance in both units
    res, agreement_t, _ = production_modes(Mt, Kt, At, COUNT)
    assert np.max(np.abs(res.omega / w - 1)) < 1e-9
    assert set(agreement_t) == set(agreement) == {KKT_CHECK, GI_CHECK}
    assert max(agreement.values()) < 1e-3 * DEFAULT_TOLERANCE
    assert max(agreement_t.values()) < 1e-3 * DEFAULT_TOLERANCE


def test_the_definite_mass_follows_the_units():
    rng = np.random.default_rng(3)
    B = rng.standard_normal((6, 6))
    K = sp.csr_array(B @ B.T + 6 * np.eye(6))
    Mm = np.diag([2.0, 3.0, 0.0, 5.0, 0.0, 1.0])
    Mm[0, 1] = Mm[1, 0] = 0.5
    M = sp.csr_array(Mm)
    S = sp.diags_array([1.0, 1e3, 1e-3, 7.0, 1e4, 1.0])
    Md = definite_mass(K, M).toarray()
    Mdt = definite_mass(sp.csr_array(S @ K @ S), sp.csr_array(S @ M @ S)).toarray()
    assert np.allclose(Mdt, S.toarray() @ Md @ S.toarray(), rtol=1e-14, atol=0)
    assert np.all(np.linalg.eigvalsh(Md) > 0)
    ratios = np.array([2 / K[0, 0], 3 / K[1, 1], 5 / K[3, 3], 1 / K[5, 5]])
    assert Md[2, 2] == pytest.approx(np.median(ratios) * K[2, 2], rel=1e-15)
