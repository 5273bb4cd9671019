"""The data ``snncc check`` measures on: a Braille data set file or a plain .npz with inputs and labels.

Inputs may come in the model's own shape: its ``base_inputs`` channels are tiled ``input_copies``
times (the authors' x.tile((k,))), as the model was trained on them, and a CNN's frames (N, T, C, H,
W) are flattened; ``meta["input_layout"]`` says what was done.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from snncc.errors import SnnccError


def load_check_data(path: Path, graph, limit: int | None = None, labels: bool = True
                    ) -> tuple[np.ndarray, np.ndarray | None, dict]:
    """(inputs, labels, meta) from a Braille data set file or a plain .npz with inputs and labels
    (``labels=False``: inputs only, labels returned as None); the first ``limit`` samples."""
    path = Path(path)
    meta: dict = {}
    from snncc.data.dataset_file import load_dataset

    if not path.is_file():
        raise SnnccError("file does not exist", file=str(path), field="--data")
    inputs = None
    if not labels:
        try:
            with np.load(path, allow_pickle=False) as z:
                inputs = np.asarray(z["inputs"])
        except Exception as ex:  # not an npz / no 'inputs'
            raise SnnccError(f"agreement needs an .npz with an array 'inputs' (N, T, C) ({type(ex).__name__})",
                             file=str(path), field="--data") from None
        inputs, meta["input_layout"] = model_layout(inputs[:limit] if limit is not None else inputs, graph)
        if inputs.ndim != 3:
            raise SnnccError(f"inputs must be (N, T, C), got shape {inputs.shape}", file=str(path), field="inputs")
        return inputs, None, meta
    try:
        inputs, labels, meta = load_dataset(path)
    except SnnccError:   # not a Braille data set: a plain .npz with inputs and labels
        inputs = None
    if inputs is None:
        try:
            with np.load(path, allow_pickle=False) as z:
                if "inputs" not in z:
                    raise SnnccError("a check data set needs arrays 'inputs' (N, T, C) and 'labels' (N,)",
                                     file=str(path), field="inputs")
                if "labels" not in z:
                    raise SnnccError("has inputs but no 'labels' (N,): pass --agreement to measure the artefact's "
                                     "agreement with the float model on these inputs instead of accuracy",
                                     file=str(path), field="labels")
                inputs, labels = z["inputs"], z["labels"]
                if "synthetic" in z and z["synthetic"].shape == () and z["synthetic"].dtype == bool:
                    meta["synthetic"] = bool(z["synthetic"])
        except SnnccError:
            raise
        except Exception as ex:  # not an npz / corrupt
            raise SnnccError(f"not a readable .npz data set ({type(ex).__name__})", file=str(path), field="--data") from None
    inputs, labels = np.asarray(inputs), np.asarray(labels)
    inputs, layout = model_layout(inputs, graph)
    if inputs.ndim != 3:
        raise SnnccError(f"inputs must be (N, T, C), got shape {inputs.shape}", file=str(path), field="inputs")
    from snncc.inputs import check_dataset

    check_dataset(inputs, labels, graph, source=str(path))
    if limit is not None:
        inputs, labels = inputs[:limit], labels[:limit]
    meta = dict(meta) if isinstance(meta, dict) else {}
    meta["input_layout"] = layout
    return inputs, labels, meta


def model_layout(inputs: np.ndarray, graph) -> tuple[np.ndarray, str | None]:
    """Inputs in the model's own shape made flat for ``graph`` (``snncc.input_layout``): CNN frames
    (N, T, C, H, W) flattened, ``base_inputs`` channels tiled ``input_copies`` times (the authors'
    x.tile((k,))); and the line saying what was done (None: nothing)."""
    from snncc.input_layout import graph_layout, to_artefact_layout

    return to_artefact_layout(np.asarray(inputs), graph_layout(graph))
