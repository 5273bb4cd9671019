"""What a target provides to be fine-tuned: a differentiable model of its own integer arithmetic.

A target builds it from its lowered (quantized) model. Its forward pass must equal the target's
bit-exact emulator on the integers ``export`` returns (each target tests this), so what the engine
optimises is what runs. Its parameters are float shadows that round to the deployed integers;
rounding passes gradients straight through and spikes use surrogate gradients
(``snncc.finetune.ste``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterator, Protocol, runtime_checkable

import torch


@dataclass
class StudentRun:
    """One forward pass in the model's own time (IR steps), model neurons only.

    counts   (B, n_out)  output spike counts over the sample (what the readout takes argmax of)
    spikes   population -> (B, T, n) 0/1 spikes (surrogate gradients)
    voltage  population -> (B, T, n) voltage before reset divided by the population's threshold
             (dimensionless, comparable with the float graph's V / theta)
    """

    counts: torch.Tensor
    spikes: dict[str, torch.Tensor] = field(default_factory=dict)
    voltage: dict[str, torch.Tensor] = field(default_factory=dict)


@runtime_checkable
class DifferentiableArithmetic(Protocol):
    """A target's integer arithmetic as a trainable torch model (e.g. ``torch.nn.Module``).

    populations   the IR LIF populations in order, the last one the output (names as in the graph)
    steps         the number of model steps T the inputs have
    forward(x, force=None) -> StudentRun
                  x: (B, T, C) 0/1 inputs in the model's channels; force: population -> (B, T, n) spikes
                  that every synapse leaving that population reads instead of its own (teacher forcing)
    param_groups() -> {kind: [parameters]}   kinds "weights", "thresholds", "decays", "biases", ...
    project()     clamp the shadows into the registers' ranges (after every optimiser step)
    export()      the target's integer network to write (e.g. a LoihiNetwork)
    state_dict() / load_state_dict()         to keep the best parameters
    """

    populations: tuple[str, ...]
    steps: int

    def forward(self, x: torch.Tensor, force: dict[str, torch.Tensor] | None = None) -> StudentRun: ...

    def param_groups(self) -> dict[str, list[torch.nn.Parameter]]: ...

    def parameters(self) -> Iterator[torch.nn.Parameter]: ...

    def project(self) -> None: ...

    def export(self) -> Any: ...

    def state_dict(self) -> dict[str, Any]: ...

    def load_state_dict(self, state: dict[str, Any]) -> Any: ...
