"""Arrays a user feeds an artefact (``emulate``, ``run``, ``check``), checked before anything runs.

    check_batch(x, width)           (T, C) or (B, T, C) -> (B, T, C): sizes, finite values, 0/1 spikes
    RandomSpikes(samples, rate, seed)  seeded random spike trains drawn at the artefact's own length
    InputLayout / to_artefact_layout   the model's own input shape (input copies, a CNN's frames) taken
    frame_shape(graph)              a convolutional model's input frame (C, H, W), or None
    load_dataset(path)              a labelled data set file (what ``snncc data`` writes)
    to_jsonable(obj)                plain JSON values from records (numpy values, dataclasses)
"""

from __future__ import annotations

from snncc.input_layout import InputLayout, frame_shape, graph_layout, to_artefact_layout
from snncc.inputs import RandomSpikes, check_batch, check_labels, load_array
from snncc.records import to_jsonable


def load_dataset(path):   # noqa: ANN001, ANN201  (the data loader is heavy: imported on use)
    """(inputs, labels, metadata) of a labelled data set file (``snncc.data.dataset_file.load_dataset``)."""
    from snncc.data.dataset_file import load_dataset as load

    return load(path)


__all__ = ["check_batch", "check_labels", "load_array", "RandomSpikes", "InputLayout", "to_artefact_layout",
           "frame_shape", "graph_layout", "load_dataset", "to_jsonable"]
