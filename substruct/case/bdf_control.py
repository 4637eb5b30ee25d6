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

__all__ = ["PARAM_TABLE", "PARAMS", "OUTPUT_PARAMS", "CASE_CONTROL", "case_command", "Eigrl",
           "read_eigrl", "read_control", "param", "select_sets", "read_uset",
           "read_static_load"]

#: Every PARAM accepted, one table: name -> (changes the model, what it does).  Those that
#: change the model are read (docs/structures.md; K6ROT only in a model without shells, where
#: it has no effect); the others, by Nastran's Quick Reference Guide, only control printing,
#: output files or post-processing (stress recovery, random response), so they cannot change
#: the modes or responses: their name and value are read and not used.
PARAM_TABLE: dict[str, tuple[bool, str]] = {
    "WTMASS": (True, "multiplies every mass"),
    "COUPMASS": (True, "coupled mass when positive"),
    "AUTOSPC": (True, "YES/NO: remove the coordinates nothing stiffens"),
    "K6ROT": (True, "the drilling stiffness of shells: in a model without shells only"),
    "POST": (False, "the files written for post-processors (OP2, XDB)"),
    "POSTEXT": (False, "extra tables in the OP2"),
    "OGEOM": (False, "the geometry tables in the OP2"),
    "PATVER": (False, "the Patran version the OP2 is written for"),
    "OUGCORD": (False, "the coordinate system of the printed displacements"),
    "GRDPNT": (False, "the printout of the grid point weight generator"),
    "PRTMAXIM": (False, "the printout of the largest displacements"),
    "PRGPST": (False, "the printout of the grid point singularity table"),
    "PRTBGPDT": (False, "the printout of the grid point table"),
    "PRTCSTM": (False, "the printout of the coordinate system table"),
    "PRTEQXIN": (False, "the printout of the grid and scalar point sequence table"),
    "PRTGPL": (False, "the printout of the grid point list"),
    "NOCOMPS": (False, "the stress output of composite plies"),
    "NOFISR": (False, "the failure indices and strength ratios of composites (stress "
                      "recovery)"),
    "SRCOMPS": (False, "the strength ratios of composite plies (stress recovery)"),
    "SPARSEDR": (False, "the method of the data recovery (sparse or not: the same results)"),
    "RPOSTS1": (False, "the post-processing of random responses"),
    "OPPHIPA": (False, "the mode shapes written at the aerodynamic points too"),
}
#: PARAM names read (they change the model).
PARAMS = tuple(k for k, (read, _) in PARAM_TABLE.items() if read)
#: PARAM names of printing, output and post-processing: read, no effect on the modes.
OUTPUT_PARAMS = tuple(k for k, (read, _) in PARAM_TABLE.items() if not read)
#: Case control commands read (titles and output requests have no effect: the mode shapes are
#: always written; ``SEALL = ALL`` and ``SUPER = ALL`` name the one residual structure;
#: ``AUTOSPC = YES/NO`` as ``PARAM,AUTOSPC``).  ``OUTPUT(...)`` starts a plot subpackage: its
#: lines (XYPRINT, ...) up to BEGIN BULK are output requests too.  As in Nastran, a command
#: may be written by its first four letters or more (``SUBT``, ``DISP``).
CASE_CONTROL = ("METHOD", "SPC", "MPC", "SUBCASE", "TITLE", "SUBTITLE", "LABEL", "ECHO",
                "DISPLACEMENT", "VECTOR", "ELFORCE", "FORCE", "STRESS", "STRAIN",
                "SPCFORCES", "MPCFORCES", "OLOAD", "GPFORCE", "ESE", "GPKE", "OUTPUT",
                "SEALL", "SUPER", "MAXLINES", "AUTOSPC")
#: Nastran case control commands not read whose first letters are those of one read: an
#: abbreviation they share with it is ambiguous (``SUBC``: SUBCASE or SUBCOM).
_OTHER_COMMANDS = ("SUBCOM", "SUBSEQ", "STRFIELD", "ECHOON", "ECHOOFF", "OUTRCV", "SUPORT1",
                   "MAXMIN", "SEDR", "SEDV", "SEFINAL", "GPSTRESS", "GPSDCON")
#: The options of the case control's ``AUTOSPC(...)`` that only control printing and
#: punching (read, no effect); any other option is refused.
_AUTOSPC_OUTPUT = ("PRINT", "NOPRINT", "PUNCH", "NOPUNCH")
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


def case_command(word: str) -> str | None:
    """The case control command ``word`` names: itself, or the one read command it
    abbreviates (its first four letters or more, Nastran's rule); ``None`` when it names none.

    Raises:
        ValueError: an abbreviation of several commands (its message names them).
    """
    if word in CASE_CONTROL:
        return word
    if len(word) < 4:
        return None
    found = [c for c in CASE_CONTROL + _OTHER_COMMANDS if c.startswith(word)]
    if len(found) > 1:
        raise ValueError(f"case control {word} is ambiguous: it abbreviates "
                         f"{' and '.join(found)} (write more of the command)")
    return found[0] if found and found[0] in CASE_CONTROL else None


def _autospc(src: str, line: int, options: str | None, value: str) -> bool:
    """``AUTOSPC[(options)] = YES|NO`` of the case control: its value; only printing and
    punching options are accepted."""
    for opt in (options or "").strip("()").split(","):
        key = opt.split("=")[0].strip()
        if key and key not in _AUTOSPC_OUTPUT:
            raise BdfError(src, f"the AUTOSPC option {key} is not supported (read: "
                           f"{', '.join(_AUTOSPC_OUTPUT)}, which only print or punch)",
                           opt.strip(), line=line, card="AUTOSPC")
    if value not in ("YES", "NO"):
        raise BdfError(src, "AUTOSPC = YES or NO", value, line=line, card="AUTOSPC")
    return value == "YES"


def read_control(text: BdfText) -> dict[str, Any]:
    """The choices of the executive and case control: ``METHOD``, ``SPC``, ``MPC`` (set ids)
    and ``AUTOSPC`` (a bool), with the line of each in ``lines``."""
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
    chosen: dict[str, Any] = {"lines": {}}
    subcases = 0
    plots = False
    for line, t in text.case_control:
        if plots:  # the plot subpackage's requests: no effect on the modes
            continue
        head = re.match(r"^[A-Z][A-Z0-9]*", t)
        written = head.group(0) if head else t.split()[0]
        try:
            command = case_command(written)
        except ValueError as err:
            raise BdfError(src, str(err), t, line=line) from None
        rest = t[len(written):]
        m = re.match(r"^\s+()(\d+)$", rest) if command == "SUBCASE" else \
            re.match(r"^\s*(\([^)]*\))?\s*(?:=\s*(.*))?$", rest)
        if not m or command is None:
            raise BdfError(src, f"case control {written} is not supported (read: "
                           f"{', '.join(CASE_CONTROL)}, or their first four letters or "
                           "more)", t, line=line)
        word = command
        if word == "OUTPUT":
            plots = True
            continue
        if word == "SUBCASE":
            subcases += 1
            if subcases > 1:
                raise BdfError(src, "one subcase is run", t, line=line)
        value = (m.group(2) or "").strip()
        if word in ("SEALL", "SUPER") and value != "ALL":
            raise BdfError(src, f"{word} = ALL is read (one residual structure, no "
                           "superelements)", t, line=line, card=word)
        if word == "AUTOSPC":
            chosen[word] = _autospc(src, line, m.group(1), value)
            chosen["lines"][word] = line
        if word in ("METHOD", "SPC", "MPC"):
            if not value.isdigit():
                raise BdfError(src, f"{word} names a set id", value, line=line, card=word)
            chosen[word] = int(value)
            chosen["lines"][word] = line
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


def select_sets(source: str, control: dict[str, Any], word: str, sets: dict[int, RawCard]
                ) -> set[int]:
    """The set ids used: the one the case control chooses, or all of a bulk-only file.
    ``sets`` maps each set id to its first card, which a refusal names.

    Raises:
        BdfError: a chosen set the bulk data does not have (naming the case control's line),
            a set not chosen (naming its first card).
    """
    if word in control:
        if control[word] not in sets:
            raise BdfError(source, f"the case control chooses {word} set {control[word]}, "
                           f"which the bulk data does not have", control[word],
                           line=control.get("lines", {}).get(word, 0), card=word)
        rest = sorted(set(sets) - {control[word]})
        if rest:
            raise sets[rest[0]].error(f"{word} set {rest[0]} is not chosen by the case "
                                      f"control ({word} = {control[word]}) and would be "
                                      "unused", rest[0])
        return {control[word]}
    if sets and control["case_control"]:
        first = sorted(sets)[0]
        raise sets[first].error(f"{word} sets {sorted(sets)} are not chosen by the case "
                                f"control (no {word} = ...) and would be unused", first)
    return set(sets)
