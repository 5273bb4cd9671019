"""Stratified, seeded train/test (and optional validation) split with scikit-learn.

The one split of the project: ``snncc data encode --split-test`` and ``snncc train`` both use it.

The paper: 80 % train / 20 % test, stratified by letter. With ``val_fraction`` > 0 a stratified
share of the *training* part is held out for selecting the epoch instead of the test set.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snncc.errors import SnnccError


@dataclass
class Split:
    train: np.ndarray   # sample indices, sorted
    test: np.ndarray
    val: np.ndarray     # empty when no validation split was asked for
    seed: int
    test_fraction: float
    val_fraction: float

    def summary(self) -> dict:
        return {"train": int(self.train.size), "val": int(self.val.size), "test": int(self.test.size),
                "seed": self.seed, "test_fraction": self.test_fraction, "val_fraction": self.val_fraction}


def stratified_split(labels: np.ndarray, *, seed: int = 0, test_fraction: float = 0.2,
                     val_fraction: float = 0.0) -> Split:
    """Indices of a stratified split; ``val_fraction`` is a share of the whole set taken from training."""
    from sklearn.model_selection import train_test_split

    labels = np.asarray(labels)
    if not 0.0 < test_fraction < 1.0:
        raise SnnccError(f"test fraction must be in (0, 1), got {test_fraction}", field="test_fraction")
    if not 0.0 <= val_fraction < 1.0 - test_fraction:
        raise SnnccError(f"validation fraction must be in [0, {1.0 - test_fraction:g}), got {val_fraction}",
                         field="--val-fraction")
    index = np.arange(labels.size)
    try:
        train, test = train_test_split(index, test_size=test_fraction, random_state=seed, stratify=labels)
        val = np.array([], dtype=np.int64)
        if val_fraction > 0:
            share = val_fraction / (1.0 - test_fraction)
            train, val = train_test_split(train, test_size=share, random_state=seed, stratify=labels[train])
    except ValueError as ex:
        raise SnnccError(f"cannot split {labels.size} samples stratified by class ({ex})", field="labels") from None
    return Split(np.sort(train), np.sort(test), np.sort(val), seed, test_fraction, val_fraction)
