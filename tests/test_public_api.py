"""Every module of the package says what it is and what it exports, and every exported
function and class is documented: a module docstring, an ``__all__`` of names that exist, and
a docstring of its own on each public function and class."""

import importlib
import inspect
import pkgutil

import pytest

import substruct

MODULES = sorted(m.name for m in pkgutil.walk_packages(substruct.__path__, "substruct."))


def _own_docstring(obj) -> bool:
    """A docstring written for ``obj``, not the signature a dataclass or a named tuple makes
    up when it has none."""
    doc = obj.__doc__
    if not doc or not doc.strip():
        return False
    return not (inspect.isclass(obj) and doc.startswith(f"{obj.__name__}("))


def test_the_walk_finds_every_layer():
    layers = {name.split(".")[1] for name in MODULES}
    assert {"case", "linalg", "substructure", "models", "assembly", "builder", "analysis",
            "run", "studies", "io", "viz", "cli"} <= layers


@pytest.mark.parametrize("name", ["substruct", *MODULES])
def test_module_is_documented_and_exports_what_it_has(name):
    module = importlib.import_module(name)
    assert inspect.getdoc(module), f"{name} has no module docstring"
    exported = getattr(module, "__all__", None)
    assert isinstance(exported, (list, tuple)), f"{name} has no __all__"
    assert all(isinstance(n, str) for n in exported), f"{name}.__all__ holds a non-string"
    assert len(set(exported)) == len(exported), f"{name}.__all__ names something twice"
    undocumented = []
    for public in exported:
        assert hasattr(module, public), f"{name}.__all__ names {public!r}, which it lacks"
        obj = getattr(module, public)
        if (inspect.isfunction(obj) or inspect.isclass(obj)) and not _own_docstring(obj):
            undocumented.append(public)
    assert not undocumented, f"{name}: no docstring on {', '.join(undocumented)}"
