"""The batched shell element matrices against the per-element reference.

``shell_matrices_batch`` computes the same quadrature with a leading element axis; each
element's matrices must equal ``shell_matrices`` of that element to round-off, relative to the
element matrix's norm (1e-12: the products involve entries of size ``E t`` and ``E t^3/L^2``
summed over a few dozen terms, so round-off is about 1e-15 of the norm).  A frame's assembled
``K`` and ``M`` must equal the sum of the per-element matrices over its faces.
"""

from __future__ import annotations

import numpy as np
import pytest

from substruct.models.beam import Material
from substruct.models.frame import frame
from substruct.models.shell import MAX_WARP, ShellTerms, shell_matrices
from substruct.models.shell_batch import shell_matrices_batch
from substruct.models.shell_mesh import Shell

E, NU, RHO = 2.1e11, 0.3, 7850.0
TERMS = {
    "plain": ShellTerms(),
    "pshell": ShellTerms(bending_material=(1.0e11, 0.25), bend=0.7, rotary=False),
    "no-membrane": ShellTerms(membrane=False),
    "no-bending": ShellTerms(bending=False),
    "mindlin": ShellTerms(shear=5 / 6 * E / (2 * (1 + NU)) * 0.004),
    "mindlin-pshell": ShellTerms(bending_material=(1.0e11, 0.25), bend=0.7, rotary=False,
                                 shear=0.9 * 4e10 * 0.004),
}


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.standard_normal((3, 3)))
    return q * np.sign(np.diag(r))


def _elements(kind: str, m: int, seed: int) -> np.ndarray:
    """``m`` distorted elements tilted in space; ``warped``: quads warped out of plane but
    within :data:`MAX_WARP`."""
    rng = np.random.default_rng(seed)
    base = np.array([[0, 0, 0], [1, 0, 0], [1.1, 0.9, 0], [0.1, 1, 0]], float)
    n = 3 if kind == "triangle" else 4
    X = base[None, :n] + 0.12 * rng.standard_normal((m, n, 3)) * np.array([1, 1, 0])
    if kind == "warped":
        X[:, :, 2] = np.array([1, -1, 1, -1]) * rng.uniform(0.2, 0.9, (m, 1)) * MAX_WARP
    return X @ _rotation(rng).T * 0.3 + rng.standard_normal(3)


def _warp(X: np.ndarray) -> float:
    ez = np.cross(X[2] - X[0], X[3] - X[1])
    ez /= np.linalg.norm(ez)
    diag = min(np.linalg.norm(X[2] - X[0]), np.linalg.norm(X[3] - X[1]))
    return float(np.abs((X - X.mean(axis=0)) @ ez).max() / diag)


@pytest.mark.parametrize("kind", ["triangle", "quad", "warped"])
@pytest.mark.parametrize("mass", ["consistent", "lumped"])
@pytest.mark.parametrize("terms", list(TERMS))
def test_batched_matrices_equal_the_per_element_ones(kind: str, mass: str, terms: str) -> None:
    X = _elements(kind, 40, seed=len(kind) + 7 * len(terms))
    if kind == "warped":
        assert 0.1 * MAX_WARP < min(_warp(x) for x in X) and max(_warp(x) for x in X) < MAX_WARP
    K, M = shell_matrices_batch(X, E, NU, 0.004, RHO, mass, 1.5, terms=TERMS[terms])
    for e, x in enumerate(X):
        Ke, Me = shell_matrices(x, E, NU, 0.004, RHO, mass, 1.5, terms=TERMS[terms])
        assert np.abs(K[e] - Ke).max() <= 1e-12 * np.linalg.norm(Ke)
        assert np.abs(M[e] - Me).max() <= 1e-12 * np.linalg.norm(Me)


@pytest.mark.parametrize("change, message", [
    (lambda X: X[3].__setitem__(slice(None), X[3][[0, 1, 3, 2]]), "not convex|not in order"),
    (lambda X: X[5].__setitem__(2, X[5][0] + np.array([0.0, 0.0, 1.0])), "warped"),
    (lambda X: X[4].__setitem__(slice(None), X[4][0]), "coincident or collinear"),
])
def test_a_refused_element_gives_its_own_message(change, message: str) -> None:
    X = _elements("quad", 8, seed=3)
    change(X)
    with pytest.raises(ValueError, match=message) as batched:
        shell_matrices_batch(X, E, NU, 0.004, RHO)
    first = next(e for e, x in enumerate(X) if _refusal(x) is not None)
    assert str(batched.value) == _refusal(X[first])


def _refusal(x: np.ndarray) -> str | None:
    try:
        shell_matrices(x, E, NU, 0.004, RHO)
    except ValueError as err:
        return str(err)
    return None


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_frame_assembly_equals_the_sum_of_per_element_matrices(mass: str) -> None:
    steel = Material(E=E, G=E / (2 * (1 + NU)), rho=RHO)
    nodes = {1: [0, 0, 0], 2: [1.2, 0, 0.1], 3: [1.3, 0.9, 0.15], 4: [0, 1, 0], 5: [0.6, 1.8, 0.3]}
    shells = [Shell((1, 2, 3, 4), 0.01, steel, (5, 4), nsm=2.0),
              Shell((4, 3, 5), 0.006, steel, (4, 4))]
    sub = frame("f", nodes, [], mass=mass, shells=shells)
    n_nodes = len(sub.meta["node_xyz"])
    K = np.zeros((6 * n_nodes, 6 * n_nodes))
    M = np.zeros_like(K)
    xyz = sub.meta["node_xyz"]
    for kind, shell, t, nsm in (("quad", shells[0], 0.01, 2.0), ("triangle", shells[1], 0.006, 0.0)):
        for face in sub.meta["faces"][kind]:
            Ke, Me = shell_matrices(xyz[list(face)], E, NU, t, RHO, mass, nsm)
            dofs = (6 * np.asarray(face)[:, None] + np.arange(6)).ravel()
            K[np.ix_(dofs, dofs)] += Ke
            M[np.ix_(dofs, dofs)] += Me
    assert len(sub.meta["faces"]["quad"]) == 20 and len(sub.meta["faces"]["triangle"]) == 16
    assert np.abs(sub.K.toarray() - K).max() <= 1e-12 * np.abs(K).max()
    assert np.abs(sub.M.toarray() - M).max() <= 1e-12 * np.abs(M).max()
