"""Blocks of the case schema whose models are imported only when a case has them.

A pydantic model's validator holds the validators of every model its fields name, so the
schema of a whole case would import, define and build every block (transient, random, test-lab
analyses, every kind of substructure...) for a case that has none of them.  A field annotated
``Annotated[Any, LazyType(module, name)]`` instead validates its value, when there is one,
with the type ``module.name`` (a model, or an annotated union of models), imported then; a
list item annotated ``Annotated[Any, LazyUnion(key, {tag: (module, name)})]`` is validated
by the model its ``key`` names.  The checks, and the errors with their locations, are the
models' own: pydantic carries a :class:`~pydantic.ValidationError` raised in a validator over
into the outer validation, its locations under the field's.  ``None`` is the value of an
absent block (its default; ``null`` in the file), as for ``Model | None``.  A type that is not
a model is validated with the configuration of the schema's models
(:class:`~substruct.case.fields.StrictModel`: no ``inf`` or ``nan``).

:func:`lazy_model` is how the case's error messages and the schema's walks find the model
behind such an annotation (it imports it).
"""

from __future__ import annotations

from importlib import import_module
from typing import Annotated, Any, Iterable, Mapping, get_args, get_origin

from pydantic import BaseModel, ConfigDict, GetCoreSchemaHandler, TypeAdapter, ValidationInfo
from pydantic_core import CoreSchema, PydanticKnownError, core_schema

__all__ = ["LazyType", "LazyUnion", "lazy_model", "lazy_members"]

#: The configuration of a type that is not a model (the schema's models' own).
_CONFIG = ConfigDict(allow_inf_nan=False)


def _import(module: str, name: str) -> Any:
    return getattr(import_module(module), name)


class LazyType:
    """The optional block ``module.name`` (a model or an annotated type), imported when a
    value is validated; ``optional=False`` (a list's items): ``None`` is validated too (and
    refused by the model, as any value that is not a mapping)."""

    def __init__(self, module: str, name: str, optional: bool = True) -> None:
        self.module, self.name, self.optional = module, name, optional
        self._adapter: TypeAdapter[Any] | None = None

    def target(self) -> Any:
        """The model class or type (its module imported now)."""
        return _import(self.module, self.name)

    def __get_pydantic_core_schema__(self, source: Any,
                                     handler: GetCoreSchemaHandler) -> CoreSchema:
        return core_schema.with_info_plain_validator_function(self._validate)

    def _validate(self, value: Any, info: ValidationInfo) -> Any:
        if value is None and self.optional:
            return None
        target = self.target()
        if isinstance(target, type) and issubclass(target, BaseModel):
            return target.model_validate(value, context=info.context)
        if self._adapter is None:
            self._adapter = TypeAdapter(target, config=_CONFIG)
        return self._adapter.validate_python(value, context=info.context)

    def __repr__(self) -> str:
        return f"LazyType({self.module!r}, {self.name!r})"


class LazyUnion:
    """A mapping validated by the model its ``key`` names (a tagged union whose members are
    imported when a case has one); the errors of a missing or unknown tag are pydantic's."""

    def __init__(self, key: str, members: Mapping[str, tuple[str, str]]) -> None:
        self.key, self.members = key, dict(members)

    def model(self, tag: Any) -> type[BaseModel] | None:
        """The member of ``tag`` (imported now), ``None`` for a tag of none."""
        found = self.members.get(tag) if isinstance(tag, str) else None
        return None if found is None else _import(*found)

    def models(self) -> list[type[BaseModel]]:
        """Every member (all imported now), in the order of :attr:`members`."""
        out: list[type[BaseModel]] = []
        for found in self.members.values():
            model = _import(*found)
            if model not in out:
                out.append(model)
        return out

    def __get_pydantic_core_schema__(self, source: Any,
                                     handler: GetCoreSchemaHandler) -> CoreSchema:
        return core_schema.with_info_plain_validator_function(self._validate)

    def _validate(self, value: Any, info: ValidationInfo) -> Any:
        if isinstance(value, BaseModel):  # a member already made: as it is
            model = self.model(getattr(value, self.key, None))
            if model is not None and isinstance(value, model):
                return value
        if not isinstance(value, dict):
            raise PydanticKnownError("model_attributes_type")
        if self.key not in value:
            raise PydanticKnownError("union_tag_not_found", {"discriminator": f"'{self.key}'"})
        model = self.model(value[self.key])
        if model is None:
            raise PydanticKnownError("union_tag_invalid", {
                "discriminator": f"'{self.key}'", "tag": str(value[self.key]),
                "expected_tags": ", ".join(f"'{t}'" for t in self.members)})
        return model.model_validate(value, context=info.context)

    def __repr__(self) -> str:
        return f"LazyUnion({self.key!r}, {sorted(self.members)})"


def _markers(annotation: Any, metadata: Iterable[Any]) -> list[Any]:
    extra = get_args(annotation)[1:] if get_origin(annotation) is Annotated else ()
    return [m for m in (*extra, *metadata) if isinstance(m, (LazyType, LazyUnion))]


def lazy_model(annotation: Any, metadata: Iterable[Any] = (), data: Any = None) -> Any:
    """The type behind an ``Annotated[Any, LazyType(...)]`` annotation, or of a field whose
    ``metadata`` (pydantic's ``FieldInfo.metadata``) holds the marker; for a
    :class:`LazyUnion`, the member that ``data`` (the mapping validated) names.  Imported now;
    ``None`` for any other annotation (or a ``data`` that names no member)."""
    for marker in _markers(annotation, metadata):
        if isinstance(marker, LazyType):
            return marker.target()
        return marker.model(data.get(marker.key)) if isinstance(data, dict) else None
    return None


def lazy_members(annotation: Any, metadata: Iterable[Any] = ()) -> list[Any]:
    """Every type an annotation with a marker may validate with (all imported now): the
    walks of the whole schema go through them."""
    out: list[Any] = []
    for marker in _markers(annotation, metadata):
        out += [marker.target()] if isinstance(marker, LazyType) else marker.models()
    return out
