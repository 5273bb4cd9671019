"""The 27 Braille classes, their labels and their dot patterns.

Label = position in ``CLASSES = ['Space', 'A', ..., 'Z']`` (the authors' ``letter_written`` list),
so ``Space -> 0``, ``A -> 1``, ..., ``Z -> 26``.
"""

from __future__ import annotations

import string

from snncc.errors import SnnccError

CLASSES: tuple[str, ...] = ("Space",) + tuple(string.ascii_uppercase)
N_CLASSES = len(CLASSES)
N_TAXELS = 12
FRAME_RATE_HZ = 40.0
_INDEX = {name: i for i, name in enumerate(CLASSES)}

# Standard six-dot Braille: dots 1-2-3 are the left column top to bottom, 4-5-6 the right.
DOTS: dict[str, tuple[int, ...]] = {
    "Space": (),
    "A": (1,), "B": (1, 2), "C": (1, 4), "D": (1, 4, 5), "E": (1, 5),
    "F": (1, 2, 4), "G": (1, 2, 4, 5), "H": (1, 2, 5), "I": (2, 4), "J": (2, 4, 5),
    "K": (1, 3), "L": (1, 2, 3), "M": (1, 3, 4), "N": (1, 3, 4, 5), "O": (1, 3, 5),
    "P": (1, 2, 3, 4), "Q": (1, 2, 3, 4, 5), "R": (1, 2, 3, 5), "S": (2, 3, 4), "T": (2, 3, 4, 5),
    "U": (1, 3, 6), "V": (1, 2, 3, 6), "W": (2, 4, 5, 6), "X": (1, 3, 4, 6), "Y": (1, 3, 4, 5, 6),
    "Z": (1, 3, 5, 6),
}


def label_of(letter: object, *, file: str | None = None, field: str | None = None) -> int:
    """Label index of a letter name (``'Space'``, ``'A'``..``'Z'``); SnnccError if unknown."""
    if isinstance(letter, str) and letter in _INDEX:
        return _INDEX[letter]
    raise SnnccError(
        f"unknown letter {letter!r} (expected one of Space, A..Z)", file=file, field=field or "letter"
    )


def letter_of(label: int) -> str:
    """Letter name of a label index 0..26."""
    if not 0 <= int(label) < N_CLASSES:
        raise SnnccError(f"label {label} outside 0..{N_CLASSES - 1}", field="labels")
    return CLASSES[int(label)]


def dot_cell(dot: int) -> tuple[int, int]:
    """(row 0..2 top to bottom, column 0 = left / 1 = right) of Braille dot 1..6."""
    return (dot - 1) % 3, (dot - 1) // 3
