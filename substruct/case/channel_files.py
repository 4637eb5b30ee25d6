"""A channel file of any kind: a table (``.csv``, ``.yaml``: :mod:`substruct.case.channels`)
or the nodes, coordinate systems and 58 functions of a Universal File (``.uff``, ``.unv``:
:mod:`substruct.case.uff_geometry`), told apart by the file's suffix."""

from __future__ import annotations

import os
from pathlib import Path

from substruct.case.channels import ChannelTable, check_channel_file, read_channel_table
from substruct.case.errors import CaseError
from substruct.case.uff_geometry import channels_from_uff

__all__ = ["read_channels"]


def read_channels(path: str | os.PathLike) -> ChannelTable:
    """The channel table of ``path``: :func:`~substruct.case.uff_geometry.channels_from_uff`
    for a ``.uff``/``.unv`` file, else
    :func:`~substruct.case.channels.read_channel_table`.

    Raises:
        CaseError: an unreadable file, an unknown suffix, or a problem with a row (a
            problem of a Universal File named by the file, as a table's is).
    """
    p = Path(path)
    if p.suffix.lower() not in (".uff", ".unv"):
        return read_channel_table(p)
    check_channel_file(p)
    source = p.name
    try:
        return channels_from_uff(p)
    except CaseError:
        raise
    except ValueError as err:
        text = str(err)
        raise CaseError(source, "", text[len(source) + 2:] if text.startswith(
            f"{source}: ") else text) from None
