"""Massless directions that are combinations of coordinates: a point mass off its node.

A CONM2 at an offset with no rotary inertia gives its node's six coordinates a mass of rank
three and no zero row.  The roots were counted from the zero rows of ``M`` only, so the dense
null-space and KKT solvers took three infinite roots for modes (exit 1, "3 of 6 values of
eigenvalues are inf or NaN"); the sparse solvers' Krylov basis was sized by the same count
and, with the Lanczos vectors left with parts in ``null(M)`` of any size, gave wrong modes
(exit 1 on the checks) or a traceback (ARPACK error 3).  The closed form: a mass ``m`` at
``r`` from a node held by springs ``k`` in its six coordinates moves along ``r`` at
``sqrt(k / m)`` and across it at ``sqrt(k / (m (1 + |r|^2)))``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg  # noqa: F401  (sp.linalg)

from cli_helpers import run
from substruct.analysis.modes.dense import coupled_modes
from substruct.analysis.modes.sparse import sparse_coupled_modes
from substruct.linalg.massless import massless_count, massless_directions
from substruct.models.craig_bampton import fixed_interface_modes
from substruct.models.reduction import undamped_modes
from substruct.substructure import Substructure

K_SPRING, MASS = 1000.0, 10.0
NODE_2, OFFSET = np.array([1.0, 2.0, -0.5]), np.array([0.3, -0.2, 0.1])


def rb0_deck(nd: int, mass: float = MASS, k: float = K_SPRING) -> str:
    """The audit's deck: the CONM2 on grid 2, joined by an RBE2 to grid 1 on six springs."""
    springs = "\n".join(f"CELAS2,{10 + c},{k:.1E},1,{c}" for c in range(1, 7))
    return (f"SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\nEIGRL,1,,,{nd}\n"
            f"GRID,1,,0.,0.,0.\nGRID,2,,1.,2.,-0.5\n{springs}\n"
            f"CONM2,21,2,,{mass:.1E},0.3,-0.2,0.1,,+C1\n+C1\nRBE2,31,1,123456,2\nENDDATA\n")


def closed_form(mass: float = MASS, k: float = K_SPRING) -> np.ndarray:
    r2 = float(np.sum((NODE_2 + OFFSET) ** 2))
    across = np.sqrt(k / (mass * (1 + r2)))
    return np.array([across, across, np.sqrt(k / mass)])


def run_deck(tmp_path, capsys, text: str, *sets: str) -> tuple[int, dict, str]:
    deck = tmp_path / "rb0.bdf"
    deck.write_text(text)
    args = ["run", deck, "--out", tmp_path / "out", "--force", "--no-pictures", "--json"]
    for s in sets:
        args += ["--set", s]
    code, out, err = run(capsys, *args)
    return code, (json.loads(out) if code == 0 else {}), err


@pytest.mark.parametrize("solver", ["dense", "sparse"])
@pytest.mark.parametrize("method", ["null-space", "kkt", "generalized-inverse"])
@pytest.mark.parametrize("scale", [1.0, 1e6])
def test_offset_mass_without_inertia_has_three_modes(tmp_path, capsys, method, solver, scale):
    """Six asked, three exist: the three against the closed form, the other roots infinite;
    in other units (mass x 1e-6, stiffness x 1e6: omega x 1e6) the same counts."""
    mass, k = MASS / scale, K_SPRING * scale
    code, res, err = run_deck(tmp_path, capsys, rb0_deck(6, mass, k),
                              f"analysis.modes.method={method}",
                              f"analysis.modes.solver={solver}")
    if method == "generalized-inverse" and solver == "dense":
        # eqs 7-10 need M definite off its zero rows: refused, pointing to the others
        assert code == 2 and "method null-space or kkt takes it" in err, err
        return
    assert code == 0, err
    omega = np.array(res["modes"]["omega"])
    ref = closed_form(mass, k)
    assert omega.size == 3
    assert np.abs(omega - ref).max() <= 1e-10 * ref.max()
    if solver == "dense":  # 2 n roots in all: 6 finite, the others set aside as infinite
        reasons = res["modes"]["spurious"]["reasons"]
        assert list(reasons) == [next(iter(reasons))] and "infinite root" in next(iter(reasons))


def test_massless_directions_of_an_offset_mass():
    """``null(M) & null(A)``: the rotations about the mass and the motions the RBE2 forbids."""
    r = NODE_2 + OFFSET
    skew = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
    T = np.hstack([np.eye(3), -skew])  # u_mass = u + theta x r
    M = MASS * T.T @ T
    Z = massless_directions(M)
    assert Z.shape[1] == 3 and np.abs(M @ Z).max() <= 1e-13 * MASS
    assert np.abs(Z.T @ Z - np.eye(3)).max() <= 1e-13
    # a constraint on one of them (theta along r held) leaves two; units do not matter
    A = np.concatenate([np.zeros(3), r / np.linalg.norm(r)])[None, :]
    S = np.diag([1e-3, 1e-3, 1e-3, 1.0, 1.0, 1.0])  # mm for m: u = S u'
    assert massless_directions(M, A).shape[1] == 2
    assert massless_directions(S @ M @ S * 1e9, A @ S).shape[1] == 2
    # the sparse count, block by block, beside a zero row and a definite block
    Ms = sp.block_diag([M, sp.csr_array((1, 1)), 2 * np.eye(6), 1e-8 * M], format="csr")
    assert massless_count(Ms) == 7


def mass_transform(offset: bool) -> np.ndarray:
    """``u_mass = T [u; theta]`` of a point mass at ``r`` from its grid (``r = 0``: on it)."""
    r = NODE_2 + OFFSET if offset else np.zeros(3)
    skew = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
    return np.hstack([np.eye(3), -skew])


def chain_with_offset_masses(nodes: int, every: int,
                             offset: bool = True) -> tuple[sp.csr_array, sp.csr_array]:
    """``nodes`` grids in a chain of springs ``k`` in all six coordinates, the first grounded,
    a point mass without inertia off every ``every``-th grid (rank three on its six; on the
    grid, ``offset`` false, its rotations are zero rows)."""
    n = 6 * nodes
    k = np.full(n, K_SPRING)
    main = k + np.concatenate([k[6:], np.zeros(6)])
    K = sp.diags_array([main, -k[6:], -k[6:]], offsets=[0, 6, -6]).tocsr()
    T = mass_transform(offset)
    blocks = [MASS * T.T @ T if (g + 1) % every == 0 else np.zeros((6, 6))
              for g in range(nodes)]
    return sp.csr_array(K), sp.block_diag(blocks, format="csr")


@pytest.mark.parametrize("offset", [True, False])
@pytest.mark.parametrize("method", ["null-space", "kkt", "generalized-inverse"])
def test_krylov_path_with_point_masses(method, offset):
    """The shift-invert Lanczos solvers on 520 grids with ten point masses (30 finite modes
    of 3120 coordinates), off their grids or on them (massless rotations: zero rows, which
    failed too, the Lanczos vectors' parts in null(M) unchecked): the lowest 20 as the dense
    pencil of the 30 directions with mass gives them (an independent formulation)."""
    K, M = chain_with_offset_masses(520, 52, offset)
    assert massless_count(M) == 3120 - 30
    got = sparse_coupled_modes(M, K, None, 20, method=method)
    # reference: K condensed onto the 30 directions with mass, M definite there
    Q = np.linalg.qr(mass_transform(offset).T)[0]  # the range of one mass block
    Z = np.zeros((3120, 30))
    for j, g in enumerate(range(51, 520, 52)):
        Z[6 * g:6 * g + 6, 3 * j:3 * j + 3] = Q
    Kf = np.linalg.inv(Z.T @ sp.linalg.spsolve(sp.csc_array(K), Z))
    Kf = (Kf + Kf.T) / 2
    ref = np.sqrt(sla.eigh(Kf, Z.T @ (M @ Z), eigvals_only=True))
    assert np.abs(got.omega - ref[:20]).max() <= 1e-8 * ref[19]
    assert np.abs(got.residual).max() <= 1e-12


def test_dense_and_sparse_count_agree_on_a_small_chain():
    """The dense pencils and the sparse count on the same model: 3 finite modes per mass."""
    K, M = chain_with_offset_masses(8, 4)
    dense = coupled_modes(M, None, K, None, method="null-space")
    assert dense.omega.size == 6 and np.all(np.isfinite(dense.omega))
    assert massless_count(M) == 48 - 6


def test_craig_bampton_fixed_interface_modes_with_offset_masses():
    """The sparse fixed-interface modes (interior above ``dense_limit``) of the chain held at
    its first grid equal the dense ones; the Lanczos basis was sized by the rows with mass
    (60, of which 30 directions have mass) and the highest modes came out 3 % off, silently."""
    K, M = chain_with_offset_masses(520, 52)
    interior = np.arange(6, K.shape[0])
    _, lam, _ = fixed_interface_modes("p", K, M, interior, 20, dense_limit=100)
    _, ref, _ = fixed_interface_modes("p", K, M, interior, 20, dense_limit=5000)
    assert np.abs(np.sqrt(lam) - np.sqrt(ref)).max() <= 1e-9 * np.sqrt(ref[-1])
    with pytest.raises(ValueError, match="30 directions with mass"):
        fixed_interface_modes("p", K, M, interior, 30, dense_limit=100)


@pytest.mark.parametrize("dense_limit", [100, 5000])
def test_modal_truncation_refuses_a_mass_without_mass_in_combinations(dense_limit):
    """Modal truncation needs ``M`` definite: the dense branch refused an offset mass without
    inertia (its Cholesky failed), the sparse one computed modes of it; both refuse now."""
    K, M = chain_with_offset_masses(400, 1)
    sub = Substructure(name="p", M=M, K=K, C=sp.csr_array(K.shape),
                       dof_labels=tuple(f"q{i}" for i in range(K.shape[0])),
                       locate=lambda point: None)
    with pytest.raises(ValueError, match="1200 combination"):
        undamped_modes(sub, 10, dense_limit=dense_limit)
