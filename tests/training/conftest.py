"""Shared fixtures of the training tests: tiny seeded toy data sets."""

import numpy as np


def toy_events(n_per_class: int = 30, n_classes: int = 3, steps: int = 20, seed: int = 0):
    """A separable event set: class c fires its own 8 of 24 channels, plus sparse noise."""
    rng = np.random.default_rng(seed)
    n = n_per_class * n_classes
    labels = np.repeat(np.arange(n_classes), n_per_class)
    x = (rng.random((n, steps, 24)) < 0.02).astype(np.uint8)
    for i, c in enumerate(labels):
        chans = np.arange(8 * c, 8 * c + 8) % 24
        x[i][:, chans] |= (rng.random((steps, 8)) < 0.5).astype(np.uint8)
    return x, labels.astype(np.int64)

