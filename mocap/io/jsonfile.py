"""Reading and writing the toolkit's JSON files with clear errors and atomic writes."""
from __future__ import annotations

import json
from pathlib import Path

from mocap.io.atomic import write_text_atomic


def read_json(path: str | Path):
    """Parse a JSON file.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ValueError
        If it is not valid JSON (the message names the file and the position).
    """
    path = Path(path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not valid JSON ({exc})") from None
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a text (JSON) file") from None


def write_json(path: str | Path, data) -> None:
    """Write ``data`` as indented JSON, atomically."""
    write_text_atomic(path, json.dumps(data, indent=2) + "\n")
