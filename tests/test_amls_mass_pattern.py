"""AMLS on a pencil whose mass couples coordinates that the stiffness does not.

The dissection must separate the pencil ``(K, M)``, not ``K`` alone: a mass entry between two
subdomains makes them exchange inertia through no separator, and the reduction, built on
the tree's structure, then either placed a child's boundary at the wrong rows of its parent's
pencil (a silently wrong eigenvalue: 2.2e-3 off with every block's modes kept, where AMLS
is exact) or failed with an IndexError (the beam column, solid block and Nastran arm of
``cases/frame_solid_links.yaml``, whose eliminated mass has 34 entries outside the
stiffness's pattern).  What is asserted:

* a spring chain with a mass coupling its two ends: every block's modes kept gives the
  dense ``eigh`` eigenvalues to round-off of the wanted one;
* a tree made from the stiffness alone is refused by the reduction, never used;
* the case ``frame_solid_links.yaml`` with ``solver: amls`` and small leaves: with every
  block's modes kept the shift-invert Lanczos frequencies to round-off; truncated, upper
  bounds within the cut-off's error.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.case.loader import load_case
from substruct.linalg.amls import amls_modes
from substruct.linalg.amls_reduce import amls_reduce
from substruct.linalg.amls_tree import dissection_tree
from substruct.run.runner import run_case

ROOT = Path(__file__).resolve().parent.parent
EPS = np.finfo(float).eps


def chain(n: int = 300) -> tuple[sp.csr_array, sp.csr_array]:
    """A fixed-free chain of unit springs and masses, the masses of its ends (and of two
    inner points) coupled: M stays positive definite, its pattern is not K's."""
    K = sp.diags_array([2 * np.ones(n), -np.ones(n - 1), -np.ones(n - 1)], offsets=[0, 1, -1])
    M = sp.lil_array(sp.eye_array(n))
    M[0, n - 1] = M[n - 1, 0] = 0.3
    M[5, 200] = M[200, 5] = 0.2
    return sp.csr_array(K), sp.csr_array(M)


def test_every_mode_kept_is_exact_when_the_mass_couples_subdomains():
    K, M = chain()
    exact = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    lam_w = 0.5 * (exact[19] + exact[20])           # 20 modes below, none at the border
    r = amls_modes(K, M, np.sqrt(lam_w), cutoff=1e3, leaf_size=20)
    assert r.n_blocks > 7                            # several levels: the coupling crosses them
    assert r.lam.size == 20
    assert np.abs(r.lam - exact[:20]).max() < 1e3 * EPS * lam_w


def test_a_tree_of_the_stiffness_alone_is_refused():
    K, M = chain()
    with pytest.raises(ValueError, match="does not separate the pencil"):
        amls_reduce(K, M, dissection_tree(K, 20), 1.0)


def frame_solid_links(solver: str, *extra: str):
    case = load_case(ROOT / "cases" / "frame_solid_links.yaml",
                     overrides=[f"analysis.modes.solver={solver}", "analysis.modes.check=[]",
                                "output.pictures=false", *extra])
    return run_case(case).modes


def test_frame_solid_links_by_amls_against_lanczos():
    exact = frame_solid_links("sparse")
    whole = frame_solid_links("amls", "analysis.modes.amls.leaf_size=20",
                              "analysis.modes.amls.cutoff=1e3")
    assert len(whole) == len(exact) == 6
    assert np.abs(whole.omega / exact.omega - 1).max() < 1e-9
    cut = frame_solid_links("amls", "analysis.modes.amls.leaf_size=20",
                            "analysis.modes.tolerance=1")
    rel = cut.omega / exact.omega - 1
    assert rel.min() > -1e-9 and rel.max() < 5e-3   # upper bounds; measured 5.4e-4
