"""Public names of a package imported on first use (PEP 562 module ``__getattr__``).

A package lists its public names and the module that defines each; importing the package
imports none of them, so ``import substruct.analysis.frf`` (or the command line's start-up)
does not pay for every module the package holds.  The first access of a name imports its
module and keeps the value in the package's namespace, so later accesses are plain lookups.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from importlib import import_module
from typing import Any

__all__ = ["lazy_getattr"]


def lazy_getattr(package: str, modules: Mapping[str, str], prefix: str = "",
                 attributes: Mapping[str, str] | None = None) -> Callable[[str], Any]:
    """The ``__getattr__`` of ``package``: ``name`` is ``getattr(module, attribute)`` where
    ``module = prefix + modules[name]`` and ``attribute = attributes.get(name, name)``.

    A name outside ``modules`` raises :class:`AttributeError`, as for any module.
    """
    renamed = dict(attributes or {})

    def __getattr__(name: str) -> Any:
        if name not in modules:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(prefix + modules[name]), renamed.get(name, name))
        setattr(sys.modules[package], name, value)
        return value

    return __getattr__
