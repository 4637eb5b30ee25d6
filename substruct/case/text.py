"""Text from a file or a user shown on a terminal: one line, nothing that controls it.

Apart from :mod:`substruct.case.errors` (which imports pydantic), so that a command that only
prints (``substruct info``) escapes its text without loading the case layer."""

from __future__ import annotations

__all__ = ["printable"]


def printable(text: str) -> str:
    """``text`` on one line with control and format characters escaped (``\\x1b``,
    ``\\u202e``), so that a value shown cannot move the cursor, retitle or clear the user's
    terminal, or reorder what it shows."""
    text = " ".join(text.splitlines())
    if text.isprintable():
        return text
    out = []
    for c in text:
        if c.isprintable():
            out.append(c)
        else:
            code = ord(c)
            out.append(f"\\x{code:02x}" if code < 0x100 else
                       f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}")
    return "".join(out)
