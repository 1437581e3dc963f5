"""Label-image conventions shared by the renderer, the image side and the costs.

A label image is a ``uint8`` array of shape ``(height, width)``:

=========  ===========================================================
value      meaning
=========  ===========================================================
0          background (not the actor)
1 .. m     colour class ``c`` (``CLASS_NAMES[c - 1]``), e.g. 1 skin, 2 clothes
255        foreground that no colour class explains ("unknown")
=========  ===========================================================
"""
from __future__ import annotations

#: Label of background pixels.
BACKGROUND: int = 0
#: Label of foreground pixels that match no colour class.
UNKNOWN: int = 255
#: Default colour classes, in label order (label = index + 1).
DEFAULT_CLASS_NAMES: tuple[str, ...] = ("skin", "clothes")
#: Most colour classes a label image can hold (labels 1..MAX_CLASSES).
MAX_CLASSES: int = 254


def class_label(name: str, class_names: tuple[str, ...] = DEFAULT_CLASS_NAMES) -> int:
    """Label value (1-based) of colour class ``name``.

    Raises
    ------
    ValueError
        If ``name`` is not one of ``class_names``.
    """
    try:
        return class_names.index(name) + 1
    except ValueError:
        raise ValueError(f"unknown colour class {name!r}; known: {', '.join(class_names)}") from None
