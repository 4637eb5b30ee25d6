"""The lines of a Nastran file with its ``INCLUDE`` statements replaced by the files they name.

``INCLUDE 'name'`` (in column 1, any case, the name in single quotes on the same line) inserts
the lines of the file ``name`` in its place, as Nastran does, in any section.  A name read
from a file is sanitised before it becomes a path:

* it is relative to the directory of the including file, and it stays inside that directory
  (no absolute path, drive, ``..`` part, or a symbolic link leading out of it);
* includes nest at most :data:`MAX_INCLUDE_DEPTH` deep, and a file that includes itself
  (directly or through others) is refused;
* the files together hold at most :data:`~substruct.case.bdf_fields.MAX_BDF_FILE` bytes, each
  checked before it is read.

Each line keeps the name of its file (the including file's name joined with the include's) and
its line number, so that messages point into the included file.
"""

from __future__ import annotations

import re
from pathlib import Path, PurePosixPath

from substruct.case.bdf_fields import MAX_BDF_FILE, BdfError, read_bdf_text

__all__ = ["MAX_INCLUDE_DEPTH", "bdf_lines", "include_name"]

#: Deepest nesting of INCLUDE statements.
MAX_INCLUDE_DEPTH = 8

#: The longest file name an INCLUDE may give (characters).
MAX_INCLUDE_NAME = 255
_INCLUDE = re.compile(r"^INCLUDE\b", re.IGNORECASE)
_QUOTED = re.compile(r"^INCLUDE\s*'([^']*)'\s*$", re.IGNORECASE)


def include_name(statement: str, source: str, line: int) -> str:
    """The file name of an ``INCLUDE 'name'`` statement, checked (module docstring).

    Raises:
        BdfError: no quoted name, an empty name, an absolute path, a drive, a ``..`` part,
            control characters.
    """
    m = _QUOTED.match(statement.split("$", 1)[0].strip())
    if m is None:
        raise BdfError(source, "INCLUDE names one file in single quotes on its line, as "
                       "INCLUDE 'part.bdf'", statement.strip(), line=line, card="INCLUDE")
    name = m.group(1).strip()
    if len(name) > MAX_INCLUDE_NAME:
        raise BdfError(source, f"an included file's name is at most {MAX_INCLUDE_NAME} "
                       "characters", name, line=line, card="INCLUDE")
    parts = PurePosixPath(name.replace("\\", "/")).parts
    if not name or any(ord(ch) < 32 for ch in name) or name.startswith(("/", "\\")) or \
            re.match(r"^[A-Za-z]:", name) or ".." in parts or "~" in name[:1]:
        raise BdfError(source, "an included file is named relative to the including file, "
                       "inside its directory (no absolute path, drive or '..')", name,
                       line=line, card="INCLUDE")
    kept = "/".join(p for p in parts if p != ".")
    if not kept:
        raise BdfError(source, "INCLUDE names a file, not the directory", name, line=line,
                       card="INCLUDE")
    return kept


def bdf_lines(path: Path, source: str) -> tuple[list[tuple[str, int, str]],
                                                list[tuple[str, int, int]]]:
    """The lines ``(file name, line number, text)`` of the bulk data file ``path`` with its
    includes inserted, and ``(resolved path, size, modification time)`` of every file read.

    Raises:
        BdfError: a file that cannot be read, an include that is not sanitary, too deep, a
            loop, or files larger than the limit together.
    """
    lines: list[tuple[str, int, str]] = []
    files: list[tuple[str, int, int]] = []
    total = [0]

    def read(p: Path, label: str, chain: tuple[str, ...]) -> None:
        text = read_bdf_text(p, label)
        total[0] += len(text)
        if total[0] > MAX_BDF_FILE:
            raise BdfError(label, f"the bulk data and its includes hold more than the "
                           f"{MAX_BDF_FILE} bytes read", total[0], card="INCLUDE")
        real = p.resolve()
        st = p.stat()
        files.append((str(real), st.st_size, st.st_mtime_ns))
        for k, raw in enumerate(text.replace("\r\n", "\n").replace("\r", "\n").split("\n")):
            if not _INCLUDE.match(raw):
                lines.append((label, k + 1, raw))
                continue
            name = include_name(raw, label, k + 1)
            if len(chain) >= MAX_INCLUDE_DEPTH:
                raise BdfError(label, f"includes nest more than {MAX_INCLUDE_DEPTH} deep",
                               name, line=k + 1, card="INCLUDE")
            base = real.parent
            target = base / name
            try:
                inside = target.resolve()
                inside.relative_to(base)
            except (OSError, ValueError):
                raise BdfError(label, "an included file stays inside the directory of the "
                               "including file (a link leads out of it)", name, line=k + 1,
                               card="INCLUDE") from None
            if not inside.is_file():
                raise BdfError(label, "no such file (an included file is a regular file "
                               "next to the including file)", name, line=k + 1,
                               card="INCLUDE")
            if str(inside) in chain:
                raise BdfError(label, "the file includes itself (through its includes)",
                               name, line=k + 1, card="INCLUDE")
            read(target, str(PurePosixPath(label).parent / name), chain + (str(inside),))

    read(path, source, (str(path.resolve()),))
    return lines, files
