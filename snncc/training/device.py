"""Where training runs: ``auto`` (CUDA when available, else the CPU), ``cpu``, ``cuda`` or ``cuda:N``.

Checkpoints are always written from CPU copies of the weights, so they load anywhere. Results are
reproducible per device for a given seed (CUDA kernels may differ from the CPU's in the last bits).
"""

from __future__ import annotations

import re

from snncc.errors import SnnccError

DEVICE_CHOICES = "auto | cpu | cuda | cuda:N"


def resolve_device(spec: str = "auto"):
    """The ``torch.device`` named by ``spec``; one-line error if it is malformed or not present."""
    import torch

    spec = (spec or "auto").strip().lower()
    if spec == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if spec == "cpu":
        return torch.device("cpu")
    match = re.fullmatch(r"cuda(?::(\d+))?", spec)
    if match is None:
        raise SnnccError(f"{spec!r} is not a device ({DEVICE_CHOICES})", field="--device")
    if not torch.cuda.is_available():
        raise SnnccError("CUDA was asked for but torch sees no CUDA device (this torch build: "
                         f"{torch.__version__}); use --device cpu or auto", field="--device")
    index = int(match.group(1) or 0)
    if index >= torch.cuda.device_count():
        raise SnnccError(f"cuda:{index} does not exist (this machine has {torch.cuda.device_count()} CUDA "
                         "device(s))", field="--device")
    return torch.device(f"cuda:{index}")
