"""Configuration dataclasses that load and save JSON, rejecting unknown or misspelt keys."""
from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T", bound="JsonConfig")


class JsonConfig:
    """Mixin for (frozen) dataclasses of plain values: ``to_dict``/``from_dict``/JSON files.

    ``from_dict`` fills missing keys with the defaults and raises ValueError for unknown keys,
    so a misspelt option never passes silently. Tuples come back as tuples.
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
        values = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items()}
        return cls(**values)

    def to_json(self, path: str | Path) -> None:
        """Write as JSON, atomically."""
        from mocap.io.jsonfile import write_json
        write_json(path, self.to_dict())

    @classmethod
    def from_json(cls: type[T], path: str | Path) -> T:
        """Read a file written by :meth:`to_json` (FileNotFoundError, ValueError)."""
        from mocap.io.jsonfile import read_json
        return cls.from_dict(read_json(path))
