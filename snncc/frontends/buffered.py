"""Checkpoints of the buffered classifiers (FCN, ResNet, Encoder, TCNN, Inception) at compile time.

They have no IR graph (their convolutions see the whole buffered sample at once), so the frontend
returns a model record (``BufferedModel``: the checkpoint's PyTorch module, its metadata and source)
that ``compile`` hands to the target's ``lower`` when the target states it takes such records
(``model_kinds`` holds "buffered": Jetson, which exports the module and checks it against PyTorch in
ONNX Runtime); any other target is refused in one line.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from snncc.errors import SnnccError

if TYPE_CHECKING:
    from snncc.frontends.load_options import LoadOptions
    from snncc.ir.graph import Graph
    from snncc.models.baselines import BufferedClassifier

SUFFIXES = (".pt", ".pth", ".ckpt")


@dataclass
class BufferedModel:
    """A buffered classifier to compile: its module, the checkpoint's metadata, the file's name and hash."""

    module: BufferedClassifier
    metadata: dict[str, Any] = field(default_factory=dict)
    source_file: str = ""
    source_sha256: str = ""
    model_kind = "buffered"      # what a target's ``model_kinds`` must hold to lower it

    @property
    def kind(self) -> str:
        return self.module.config.kind


def read_buffered(path: str | Path, options: LoadOptions | None = None) -> BufferedModel | None:
    """The buffered classifier in ``path``, or None when ``path`` holds another model (or is not a
    readable torch file: the regular loader then says why). Load options are refused as for any
    snncc checkpoint (its architecture record states dt and reset)."""
    p = Path(path)
    if p.suffix.lower() not in SUFFIXES or not p.is_file():
        return None
    from snncc.atomic import file_sha256
    from snncc.interrupts import sigint_deferred

    with sigint_deferred():   # torch's C++ start-up aborts on a Ctrl-C inside it (as in frontends._resolve)
        from snncc.frontends.checkpoint import is_checkpoint, model_metadata, module_from_checkpoint
        from snncc.frontends.load_options import refuse_options
        from snncc.frontends.torchfile import load_torch_file
        from snncc.models.baselines import BASELINE_KINDS

    try:
        obj = load_torch_file(p)
    except SnnccError:
        return None
    if not (is_checkpoint(obj) and isinstance(obj.get("architecture"), dict)
            and obj["architecture"].get("kind") in BASELINE_KINDS):
        return None
    refuse_options(options, (), "an snncc checkpoint, whose architecture record states dt and reset", p)
    module = module_from_checkpoint(obj, source=str(p))
    return BufferedModel(module, model_metadata(obj), p.name, file_sha256(p))


def load_compilable(path: str | Path, options: LoadOptions | None = None) -> Graph | BufferedModel:
    """What ``compile`` lowers: a buffered classifier's record, else the validated IR graph (``load_model``)."""
    from snncc.frontends import load_model

    return read_buffered(path, options) or load_model(path, options)
