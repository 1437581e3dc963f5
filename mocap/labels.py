"""Label-image conventions shared by the renderer, the image side and the costs.

A label image is a ``uint8`` array of shape ``(height, width)``:

=========  ===========================================================
value      meaning
=========  ===========================================================
0          background (not the actor)
1 .. m     colour class ``c`` (``class_names[c - 1]``), e.g. 1 skin, 2 clothes
255        foreground that no colour class explains ("unknown")
=========  ===========================================================

The default classes are the paper's two (skin, clothes) and two more that let the costs see
what the paper's model leaves unexplained: hair (which tells the back of the head from the
face) and the lower body (trousers or skirt under the torso). A person without one of them (no
visible hair, trousers the colour of the shirt) has the class merged into the one it stands
in for (:data:`CLASS_MERGES_INTO`).
"""
from __future__ import annotations

from types import MappingProxyType

#: Label of background pixels.
BACKGROUND: int = 0
#: Label of foreground pixels that match no colour class.
UNKNOWN: int = 255
#: The paper's colour classes, in label order (label = index + 1).
PAPER_CLASS_NAMES: tuple[str, ...] = ("skin", "clothes")
#: Default colour classes, in label order (label = index + 1).
DEFAULT_CLASS_NAMES: tuple[str, ...] = PAPER_CLASS_NAMES + ("hair", "lower_body")
#: Optional classes and the class each merges into when the image does not support it.
CLASS_MERGES_INTO = MappingProxyType({"hair": "skin", "lower_body": "clothes"})
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


def merged_class(name: str, class_names: tuple[str, ...]) -> str:
    """The class of ``class_names`` that stands for ``name``: ``name`` itself, or the class it
    merges into (:data:`CLASS_MERGES_INTO`, followed as far as needed).

    Raises
    ------
    ValueError
        If neither ``name`` nor any class it merges into is in ``class_names``.
    """
    seen = name
    while seen not in class_names:
        if seen not in CLASS_MERGES_INTO:
            raise ValueError(f"colour class {name!r} is not one of {class_names} and merges into none of them")
        seen = CLASS_MERGES_INTO[seen]
    return seen
