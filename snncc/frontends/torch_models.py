"""``.pt`` files: snncc checkpoints and the authors' SpyTorch weight lists, told apart by content."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import torch

from snncc.errors import SnnccError
from snncc.frontends.checkpoint import is_checkpoint, model_metadata, module_from_checkpoint
from snncc.frontends.module import graph_from_module
from snncc.frontends.spytorch import is_weight_list, load_weight_list
from snncc.frontends.torchfile import load_torch_file
from snncc.ir.graph import Graph
from snncc.models.baselines import BufferedClassifier


def from_object(obj: Any, path: Path, options) -> Graph:
    from snncc.frontends.load_options import refuse_options

    if isinstance(obj, torch.nn.Module):
        refuse_options(options, (), "an snncc model, whose architecture states dt and reset", path)
        return graph_from_module(obj)
    if is_checkpoint(obj):
        refuse_options(options, (), "an snncc checkpoint, whose architecture record states dt and reset", path)
        module = module_from_checkpoint(obj, source=str(path))
        if isinstance(module, BufferedClassifier):
            raise SnnccError(f"a {module.config.kind} (convolutional, buffered) has no IR graph: compile it with "
                             "--target jetson (checked against PyTorch in ONNX Runtime)", file=str(path),
                             field="architecture.kind")
        return graph_from_module(module, metadata={**model_metadata(obj), "source_format": "snncc-checkpoint"})
    if is_weight_list(obj):
        refuse_options(options, ("params",), "a SpyTorch weight list, whose parameters file (--params) states dt "
                       "and whose reset is the authors' (to zero)", path)
        return load_weight_list(obj, path, options.params)
    if isinstance(obj, dict) and all(isinstance(v, torch.Tensor) for v in obj.values()):
        raise SnnccError("a bare state dict has no architecture record; save an snncc checkpoint "
                         "(snncc.frontends.checkpoint.save_checkpoint) or the authors' weight list",
                         file=str(path), field="contents")
    kind = type(obj).__name__
    raise SnnccError(f"holds a {kind}, which is neither an snncc checkpoint nor a SpyTorch weight list "
                     "([W_in, W_out(, V_rec)])", file=str(path), field="contents")


def load(path: Path, options) -> Graph:
    return from_object(load_torch_file(path), path, options)
