r"""PBEAM, the CBEAM property, with all its lines: end A, the stations (``SO X/XB`` lines, each
followed by its stress points when ``SO`` is ``YES``), the shear factors and the warping and
offset lines.  Field indices as in :mod:`substruct.case.bdf_cards` (``fields[8 k + j]`` is
field ``j + 2`` of line ``k + 1``).

What is read, with Nastran's meaning (MSC Nastran Quick Reference Guide, PBEAM):

* end A: ``A, I1, I2, J, NSM`` (``I12`` must be 0);
* one station at end B (``X/XB = 1.0``) whose section equals end A's to 0.1 % (a blank field
  takes end A's value): the element's section is the mean of the two ends, the first-order
  stiffness of a linear taper that small (its second-order part is below ``(0.1 %)^2``);
  intermediate stations and larger tapers are refused;
* ``K1``, ``K2``: the shear factors of planes 1 and 2, shear stiffness :math:`K_i A G`
  (Timoshenko, :math:`\phi_i = 12 E I_i / (K_i G A L^2)`), 1.0 when blank; 0.0 leaves the
  plane without shear flexibility (Euler-Bernoulli);
* ``S1, S2`` (shear relief of a taper), ``NSI`` (non-structural inertia), ``CW`` (warping)
  and the offsets ``M1 .. N2`` must be 0; the stress points are read and not used.
"""

from __future__ import annotations

from substruct.case.bdf_fields import RawCard

__all__ = ["read_pbeam", "TAPER_TOLERANCE"]

#: Largest relative difference between the ends of a PBEAM read as one section.
TAPER_TOLERANCE = 1e-3
_SECTION = ("A", "I1", "I2", "I12", "J", "NSM")


def _line_is_station(c: RawCard, line: int) -> bool:
    return c.text(8 * line) in ("YES", "YESA", "NO")


def read_pbeam(c: RawCard) -> tuple[int, int, float, float, float, float, float, float, float]:
    """PBEAM (module docstring): ``(pid, mid, A, I1, I2, J, nsm, K1, K2)``.

    Raises:
        BdfError: a field that is not supported (intermediate stations, a taper above
            0.1 %, I12, S1, S2, NSI, CW, M1 .. N2 not 0), naming it.
    """
    end_a = [c.real(2, "A")] + [c.real(3 + k, f"{n}(A)", 0.0) for k, n in
                                enumerate(_SECTION[1:])]
    if end_a[3] != 0.0:
        raise c.error("unsymmetric sections (I12) are not supported", c.text(5), "I12")
    for k in range(8, 16):  # stress points of end A: read, not used
        c.real(k, f"field {k % 8 + 2} of line 2", 0.0)
    line = 2
    section = list(end_a)
    while _line_is_station(c, line):
        base = 8 * line
        if line > 2:
            raise c.error("one station (end B) is supported: intermediate stations are not",
                          c.text(base), "SO")
        xb = c.real(base + 1, "X/XB", 1.0)
        if xb != 1.0:
            raise c.error("only the station at end B (X/XB = 1.0) is supported", xb, "X/XB")
        end_b = [c.real(base + 2 + k, f"{n}(B)", end_a[k]) for k, n in enumerate(_SECTION)]
        for k, name in enumerate(_SECTION):
            scale = max(abs(end_a[k]), abs(end_b[k]))
            if abs(end_b[k] - end_a[k]) > TAPER_TOLERANCE * scale:
                raise c.error(f"tapered sections are not supported: {name} at end B differs "
                              f"from end A ({end_a[k]!r}) by more than "
                              f"{TAPER_TOLERANCE:.1%}", end_b[k], f"{name}(B)")
        section = [(a + b) / 2 for a, b in zip(end_a, end_b)]
        line += 1
        if c.text(base) == "YES":  # its stress points: read, not used
            for k in range(8 * line, 8 * line + 8):
                c.real(k, f"field {k % 8 + 2} of line {line + 1}", 0.0)
            line += 1
    base = 8 * line
    k1, k2 = c.real(base, "K1", 1.0), c.real(base + 1, "K2", 1.0)
    for value, name in ((k1, "K1"), (k2, "K2")):
        if value < 0:
            raise c.error("must not be negative", value, name)
    names = ("S1", "S2", "NSI(A)", "NSI(B)", "CW(A)", "CW(B)", "M1(A)", "M2(A)", "M1(B)",
             "M2(B)", "N1(A)", "N2(A)", "N1(B)", "N2(B)")
    for k, name in enumerate(names, start=base + 2):
        if c.real(k, name, 0.0) != 0.0:
            raise c.error("shear relief, non-structural inertia, warping and offsets of the "
                          "neutral axis or of the non-structural mass are not supported",
                          c.text(k), name)
    c.blank_after(base + 16, "PBEAM ends with the K1 K2 and M1 .. N2 lines")
    A, I1, I2, _, J, nsm = section
    return c.integer(0, "PID"), c.integer(1, "MID"), A, I1, I2, J, nsm, k1, k2
