"""Data shaped to a bundle's input layer: channels tiled to its width (input copies), time cut or
zero-padded to its tSample."""

from __future__ import annotations

import numpy as np

from snncc.targets.kit import SnnccError


def fit_to_bundle(x: np.ndarray, network, source: str) -> tuple[np.ndarray, str]:
    """(T, C) or (B, T, C) data -> (B, tSample, input_width) and a note of what was changed ("" if nothing).

    C must divide the input width (k = width / C copies, the authors' x.tile((k,)))."""
    if x.ndim == 2:
        x = x[None]
    if x.ndim != 3:
        raise SnnccError(f"inputs must be (T, C) or (B, T, C), got shape {x.shape}", file=source, field="inputs")
    width = network.input_width
    notes = []
    if x.shape[2] != width:
        if width % x.shape[2]:
            raise SnnccError(f"inputs have {x.shape[2]} channels; the bundle's input layer has {width}",
                             file=source, field="inputs")
        k = width // x.shape[2]
        x = np.tile(x, (1, 1, k))
        notes.append(f"channels tiled x{k} (input copies)")
    t = network.t_sample
    if x.shape[1] < t:
        x = np.concatenate([x, np.zeros((x.shape[0], t - x.shape[1], x.shape[2]), x.dtype)], axis=1)
        notes.append(f"padded with zeros to tSample {t}")
    elif x.shape[1] > t:
        x = x[:, :t]
        notes.append(f"cut to tSample {t}")
    return x, "; ".join(notes)
