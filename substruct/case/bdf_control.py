"""What a Nastran file asks for: its executive and case control (``SOL 103``; ``METHOD``,
``SPC`` and ``MPC`` choosing sets), its ``PARAM`` values and its EIGRL (the modes wanted).

**Sets.** The case control's ``METHOD``, ``SPC`` and ``MPC`` choose the EIGRL, SPC/SPC1 and
MPC sets, as in Nastran.  A set in the file that the case control does not choose is refused
(it would be silently unused); a file of bulk data only uses all its SPC and MPC cards and its
one EIGRL.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from substruct.case.bdf_fields import BdfError, BdfText, RawCard

__all__ = ["PARAMS", "OUTPUT_PARAMS", "CASE_CONTROL", "Eigrl", "read_eigrl", "read_control",
           "param", "select_sets", "read_uset", "read_static_load"]

#: PARAM names read (K6ROT only in a model without shells, where it has no effect).
PARAMS = ("WTMASS", "COUPMASS", "AUTOSPC", "K6ROT")
#: PARAM names of output requests: read, no effect on the modes.
OUTPUT_PARAMS = ("POST", "POSTEXT", "OUGCORD", "GRDPNT", "PRTMAXIM", "NOCOMPS")
#: Case control commands read (titles and output requests have no effect: the mode shapes are
#: always written; ``SEALL = ALL`` and ``SUPER = ALL`` name the one residual structure).
#: ``OUTPUT(...)`` starts a plot subpackage: its lines (XYPRINT, ...) up to BEGIN BULK are
#: output requests too.
CASE_CONTROL = ("METHOD", "SPC", "MPC", "SUBCASE", "TITLE", "SUBTITLE", "LABEL", "ECHO",
                "DISPLACEMENT", "DISP", "VECTOR", "ELFORCE", "ELFOR", "FORCE", "STRESS",
                "STRAIN", "SPCFORCES", "MPCFORCES", "OLOAD", "GPFORCE", "ESE", "GPKE",
                "OUTPUT", "SEALL", "SUPER", "MAXLINES")
_EXECUTIVE = ("SOL", "ID", "TIME", "DIAG", "ASSIGN")
#: ASSIGN statements of output files (read, no effect: the results go to the run's HDF5).
_ASSIGN_OUTPUTS = ("OUTPUT2", "OUTPUT4", "PUNCH", "OP2")


@dataclass(frozen=True)
class Eigrl:
    """EIGRL: set ``sid``, frequency range ``v1``-``v2`` (Hz, ``None`` when blank), ``nd``,
    the shapes' normalisation ``norm`` (``MASS`` or ``MAX``)."""

    sid: int
    v1: float | None
    v2: float | None
    nd: int | None
    line: int
    norm: str = "MASS"


def read_eigrl(c: RawCard) -> Eigrl:
    """EIGRL SID V1 V2 ND MSGLVL MAXSET SHFSCL NORM (V1, V2 in Hz; NORM MASS or MAX: ``substruct
    run`` of the file refuses MAX, which its shapes would not honour; a file used as a
    substructure does not use its EIGRL)."""
    c.blank_after(8, "EIGRL option lines are not supported")
    norm = c.text(7) or "MASS"
    if norm not in ("MASS", "MAX"):
        raise c.error("must be MASS or MAX", norm, "NORM")
    v1 = c.real(1, "V1") if c.text(1) else None
    v2 = c.real(2, "V2") if c.text(2) else None
    nd = c.integer(3, "ND") if c.text(3) else None
    if nd is not None and nd <= 0:
        raise c.error("must be positive", nd, "ND")
    if nd is None and v2 is None:
        raise c.error("EIGRL needs ND or V2 (the modes wanted)", name="ND")
    if v1 is not None and v2 is not None and v2 <= v1:
        raise c.error("V2 must be above V1", v2, "V2")
    return Eigrl(c.integer(0, "SID"), v1, v2, nd, c.line, norm)


def read_control(text: BdfText) -> dict[str, Any]:
    """The choices of the executive and case control (``METHOD``, ``SPC``, ``MPC``)."""
    src = text.source
    for line, t in text.executive:
        word = t.split()[0].split(",")[0]
        if word not in _EXECUTIVE:
            raise BdfError(src, f"executive control {word} is not supported (read: "
                           f"{', '.join(_EXECUTIVE)}, CEND)", t, line=line)
        if word == "SOL" and t.split()[1:2] not in (["103"], ["SEMODES"]):
            raise BdfError(src, "only normal modes, SOL 103, are run", t, line=line)
        if word == "ASSIGN" and (re.split(r"[\s=]+", t) + [""])[1] not in _ASSIGN_OUTPUTS:
            raise BdfError(src, f"ASSIGN of output files ({', '.join(_ASSIGN_OUTPUTS)}) is "
                           "read, no other", t, line=line)
    chosen: dict[str, Any] = {}
    subcases = 0
    plots = False
    for line, t in text.case_control:
        if plots:  # the plot subpackage's requests: no effect on the modes
            continue
        m = re.match(r"^([A-Z]+)\s*(\([^)]*\))?\s*(?:=\s*(.*))?$", t) or \
            re.match(r"^(SUBCASE)\s+()(\d+)$", t)
        word = m.group(1) if m else t.split()[0]
        if not m or word not in CASE_CONTROL:
            raise BdfError(src, f"case control {word} is not supported (read: "
                           f"{', '.join(CASE_CONTROL)})", t, line=line)
        if word == "OUTPUT":
            plots = True
            continue
        if word == "SUBCASE":
            subcases += 1
            if subcases > 1:
                raise BdfError(src, "one subcase is run", t, line=line)
        if word in ("SEALL", "SUPER") and (m.group(3) or "").strip() != "ALL":
            raise BdfError(src, f"{word} = ALL is read (one residual structure, no "
                           "superelements)", t, line=line, card=word)
        if word in ("METHOD", "SPC", "MPC"):
            value = (m.group(3) or "").strip()
            if not value.isdigit():
                raise BdfError(src, f"{word} names a set id", value, line=line, card=word)
            chosen[word] = int(value)
    chosen["case_control"] = bool(text.case_control or text.executive)
    return chosen


def read_uset(c: RawCard) -> tuple[str, list[tuple[int, str]]]:
    """USET SNAME ID1 C1 ID2 C2 ...: a user set (output, DMAP); read, no effect on the modes."""
    name = c.text(0)
    if not re.fullmatch(r"[A-Z][A-Z0-9]{0,7}", name):
        raise c.error("must be a set name", name, "SNAME")
    pairs = []
    for k in range(1, 7, 2):
        if c.text(k) or c.text(k + 1):
            pairs.append((c.integer(k, f"ID{k // 2 + 1}"), c.text(k + 1)))
    c.blank_after(7, "USET has one line")
    if not pairs:
        raise c.error("a set needs a grid", name="ID1")
    return name, pairs


def read_static_load(c: RawCard) -> None:
    """LOAD SID S S1 L1 S2 L2 ... and FORCE SID G CID F N1 N2 N3: static loads, which the case
    control of a normal modes run cannot choose (``LOAD =`` is refused there): their fields
    are checked and they have no effect."""
    c.integer(0, "SID")
    if c.name == "FORCE":
        c.blank_after(7, "FORCE has one line")
        c.integer(1, "G")
        c.integer(2, "CID", 0)
        for k, name in ((3, "F"), (4, "N1"), (5, "N2"), (6, "N3")):
            c.real(k, name, 0.0)
        return
    c.real(1, "S")
    for k in range(2, len(c.fields), 2):
        n = k // 2
        c.real(k, f"S{n}")
        c.integer(k + 1, f"L{n}")


def param(params: dict[str, tuple[RawCard, str]], key: str, kind: str, default: Any) -> Any:
    """The value of ``PARAM,key`` read as ``kind`` (``default`` when the deck has none)."""
    if key not in params:
        return default
    card, text = params[key]
    if kind == "real":
        return card.real(1, "V1")
    if kind == "int":
        return card.integer(1, "V1")
    if text not in ("YES", "NO"):
        raise card.error("must be YES or NO", text, "V1")
    return text == "YES"


def select_sets(source: str, control: dict[str, Any], word: str, sets: set[int]) -> set[int]:
    """The set ids used: the one the case control chooses, or all of a bulk-only file."""
    if word in control:
        if control[word] not in sets:
            raise BdfError(source, f"the case control chooses {word} set {control[word]}, "
                           f"which the bulk data does not have", control[word], card=word)
        rest = sorted(sets - {control[word]})
        if rest:
            raise BdfError(source, f"{word} set {rest[0]} is not chosen by the case control "
                           f"({word} = {control[word]}) and would be unused", rest[0],
                           card=word)
        return {control[word]}
    if sets and control["case_control"]:
        raise BdfError(source, f"{word} sets {sorted(sets)} are not chosen by the case "
                       f"control (no {word} = ...) and would be unused", sorted(sets)[0],
                       card=word)
    return sets
