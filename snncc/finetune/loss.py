"""The distillation loss: how far the student's run is from the teacher's on the same inputs.

Terms (each weighted; weight 0 leaves it out), with c the output counts, s spikes, V the voltage
before reset over the threshold, mean over samples and neurons:

    counts    ((c_student - c_teacher) / mean(c_teacher))**2                   output spike counts
    ce        cross-entropy of softmax(c_student / tau) with the teacher's argmax, on the samples whose
              teacher counts have one clear winner
    windows   (sum of s_student - s_teacher over windows of ``window`` steps)**2, hidden populations
    voltage   (clip(V_student, -2, 2) - clip(V_teacher, -2, 2))**2, hidden populations

Which terms work, and with which weights, was measured (docs/finetune.md): output-only terms
(counts, ce, a KL divergence of softmaxed counts) barely move held-out agreement; the hidden
windows under teacher forcing do.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import torch

from snncc.errors import SnnccError

VOLTAGE_CLIP = 2.0


@dataclass(frozen=True)
class LossWeights:
    counts: float = 1.0
    ce: float = 0.0
    windows: float = 1.0
    voltage: float = 0.0
    window: int = 16          # steps per window of the ``windows`` term
    tau: float = 2.0          # softmax temperature of the ``ce`` term (spike counts)

    def __post_init__(self) -> None:
        for name in ("counts", "ce", "windows", "voltage"):
            value = getattr(self, name)
            if not value >= 0:
                raise SnnccError(f"loss weights must be >= 0, got {value}", field=f"loss.{name}")
        if not (isinstance(self.window, int) and self.window >= 1):
            raise SnnccError(f"must be a whole number of steps >= 1, got {self.window}", field="loss.window")
        if not self.tau > 0:
            raise SnnccError(f"must be > 0, got {self.tau}", field="loss.tau")

    def as_dict(self) -> dict:
        return asdict(self)


def _windowed(s: torch.Tensor, window: int) -> torch.Tensor:
    b, t, n = s.shape
    k = max(1, t // window)
    return s[:, :k * window].reshape(b, k, -1, n).sum(2)


def distillation_loss(run, teacher: dict, weights: LossWeights, hidden: tuple[str, ...]) -> torch.Tensor:
    """The weighted loss of a ``StudentRun`` against teacher tensors ``{"counts", "spikes", "voltage"}``."""
    ct = teacher["counts"]
    cs = run.counts
    total = cs.new_zeros(())
    if weights.counts:
        total = total + weights.counts * (((cs - ct) / ct.mean().clamp_min(1.0)) ** 2).mean()
    if weights.ce:
        top = torch.sort(ct, dim=1).values
        clear = top[:, -1] > top[:, -2]
        if bool(clear.any()):
            total = total + weights.ce * torch.nn.functional.cross_entropy(cs[clear] / weights.tau,
                                                                           ct[clear].argmax(1))
    for p in hidden:
        if weights.windows:
            d = _windowed(run.spikes[p], weights.window) - _windowed(teacher["spikes"][p], weights.window)
            total = total + weights.windows * (d ** 2).mean()
        if weights.voltage:
            vs = run.voltage[p].clamp(-VOLTAGE_CLIP, VOLTAGE_CLIP)
            vt = teacher["voltage"][p].clamp(-VOLTAGE_CLIP, VOLTAGE_CLIP)
            total = total + weights.voltage * ((vs - vt) ** 2).mean()
    return total
