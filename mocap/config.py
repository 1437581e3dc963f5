"""Configuration dataclasses that load and save JSON, rejecting unknown or misspelt keys."""
from __future__ import annotations

import dataclasses
import math
import types
import typing
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T", bound="JsonConfig")

#: How each plain type is named in error messages (JSON's words).
_TYPE_WORDS = {bool: "a JSON boolean (true or false)", int: "an integer", float: "a number", str: "a string"}


def _describe(hint) -> str:
    """Words for a field's type hint, e.g. ``a list of integers``."""
    if hint in _TYPE_WORDS:
        return _TYPE_WORDS[hint]
    args = typing.get_args(hint)
    if typing.get_origin(hint) is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return f"a list of ({_describe(args[0])})"
        return f"a list of {len(args)} items ({', '.join(_describe(a) for a in args)})"
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        return " or ".join("null" if a is type(None) else _describe(a) for a in args)
    return getattr(hint, "__name__", str(hint))


def _typed(hint, value):
    """``value`` converted to the field type ``hint`` (lists to tuples), or TypeError.

    Strict: a boolean is never a number (nor a number a boolean), a string never a number; an
    integer is accepted where a float is expected; floats must be finite.
    """
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is bool:
        if isinstance(value, bool):
            return value
    elif hint is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    elif hint is float:
        if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
            return value
    elif hint is str:
        if isinstance(value, str):
            return value
    elif isinstance(hint, type) and issubclass(hint, JsonConfig):      # a nested settings object
        if isinstance(value, hint):
            return value
        if isinstance(value, dict):
            return hint.from_dict(value)        # its own ValueError names the bad key
    elif origin is tuple:
        if isinstance(value, (list, tuple)):
            if len(args) == 2 and args[1] is Ellipsis:
                return tuple(_typed(args[0], v) for v in value)
            if len(value) == len(args):
                return tuple(_typed(a, v) for a, v in zip(args, value))
    elif origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        for a in args:
            if a is not type(None):
                try:
                    return _typed(a, value)
                except TypeError:
                    pass
    else:                                   # a type the configs do not use: accepted as it is
        return value
    raise TypeError(value)


class JsonConfig:
    """Mixin for (frozen) dataclasses of plain values: ``to_dict``/``from_dict``/JSON files.

    ``from_dict`` fills missing keys with the defaults and raises ValueError for unknown keys,
    so a misspelt option never passes silently, and for a value of another type than the
    field's annotation (derived from the type hints: ``"no"`` or ``0`` for a boolean, ``true``
    or ``"3"`` for a number, ``2.5`` for an integer). Tuples come back as tuples.
    """

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)  # type: ignore[arg-type]

    @classmethod
    def from_dict(cls: type[T], data: dict[str, Any]) -> T:
        if not isinstance(data, dict):
            raise ValueError(f"{cls.__name__} must be a JSON object, got {type(data).__name__}")
        fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
        unknown = set(data) - set(fields)
        if unknown:
            raise ValueError(f"unknown {cls.__name__} option(s): {', '.join(sorted(unknown))}; "
                             f"known: {', '.join(fields)}")
        hints = typing.get_type_hints(cls)
        values = {}
        for key, value in data.items():
            try:
                values[key] = _typed(hints[key], value)
            except TypeError:
                raise ValueError(f"{cls.__name__} option {key} must be {_describe(hints[key])}, "
                                 f"got {value!r}") from None
        return cls(**values)

    def to_json(self, path: str | Path) -> None:
        """Write as JSON, atomically."""
        from mocap.io.files import write_json
        write_json(path, self.to_dict())

    @classmethod
    def from_json(cls: type[T], path: str | Path) -> T:
        """Read a file written by :meth:`to_json` (FileNotFoundError, ValueError)."""
        from mocap.io.files import read_json
        try:
            return cls.from_dict(read_json(path))
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None
