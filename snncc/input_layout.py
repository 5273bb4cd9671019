"""Inputs in the model's own shape, read into the flat channels an artefact takes.

Data may come shaped as the model was trained on it:

* frames ``(B, T, C, H, W)`` (or ``(T, C, H, W)``) of a convolutional model whose input frame is
  ``(C, H, W)`` (``frame_shape``): flattened in C order to ``C*H*W`` channels (the order of the
  model's own flatten);
* the data's own channels when the artefact takes ``k`` copies of them (the authors' RSNN: 24 event
  channels fed twice, 48 input axons): tiled ``k`` times along the channel axis, as the authors'
  ``x.tile((k,))``.

The flattened form (the artefact's own width) is taken as it is. ``to_artefact_layout`` returns the
array and one line saying what it did (None when it did nothing); anything else is left for the
caller's width check to refuse in one line.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class InputLayout:
    width: int                          # channels the artefact takes (always-on bias axons excluded)
    copies: int = 1                     # the artefact takes ``copies`` copies of ``base`` channels
    base: int | None = None             # the data's own channels
    frame: tuple[int, ...] | None = None   # one input frame (C, H, W) of a convolutional model

    @classmethod
    def from_record(cls, width: int, record: dict) -> "InputLayout":
        """From an artefact's recorded metadata (``input_copies``, ``base_inputs``, ``input_shape``)."""
        copies = int(record.get("input_copies") or 1)
        base = record.get("base_inputs")
        frame = record.get("input_shape")
        return cls(width=int(width), copies=copies, base=None if base is None else int(base),
                   frame=tuple(int(v) for v in frame) if frame else None)


def frame_shape(graph) -> list[int] | None:
    """The shape of one input frame as the model was trained on it, (C, *spatial): the ``in_shape`` of
    the convolution the Input feeds, else None (the input is a flat channel vector)."""
    from snncc.ir.nodes import Conv, Input

    for name in graph.of_kind(Input):
        for succ in graph.successors(name):
            op = graph.node(succ)
            if isinstance(op, Conv):
                return [int(v) for v in op.in_shape]
    return None


def to_artefact_layout(x, layout: InputLayout) -> tuple[np.ndarray, str | None]:
    """``x`` in the artefact's flat layout (T, W) / (B, T, W), and the line that says what was done."""
    x = np.asarray(x)
    notes = []
    frame = layout.frame
    if frame and x.ndim in (len(frame) + 1, len(frame) + 2) and tuple(x.shape[-len(frame):]) == tuple(frame):
        flat = int(np.prod(frame))
        shown = "x".join(str(v) for v in frame)
        x = x.reshape(x.shape[:-len(frame)] + (flat,))
        notes.append(f"read frames of {shown} as {flat} channels (C order, the model's own flattening)")
    if x.ndim in (2, 3) and layout.copies > 1 and layout.base and x.shape[-1] == layout.base != layout.width \
            and layout.base * layout.copies == layout.width:
        x = np.tile(x, (1,) * (x.ndim - 1) + (layout.copies,))
        notes.append(f"tiled the data's {layout.base} channels {layout.copies} times to the artefact's {layout.width} "
                     "inputs (the model's input copies, recorded in the artefact)")
    return x, ("; ".join(notes) or None)


def graph_layout(graph) -> InputLayout:
    """The layout of a model's own input: its Input's width, input copies and frame shape."""
    from snncc.ir.nodes import Input

    width = int(graph.node(graph.of_kind(Input)[0]).width)
    k = int(graph.metadata.get("input_copies", 1) or 1)
    base = graph.metadata.get("base_inputs")
    frame = frame_shape(graph)
    return InputLayout(width=width, copies=k, base=None if base is None else int(base),
                       frame=tuple(frame) if frame else None)
