"""The paper's optimised hyper-parameters per encoding threshold (table of HPO results).

| th | scale | time_bin_size ms | nb_input_copies | tau_mem s | tau_ratio | fwd_weight_scale | weight_scale_factor | reg_spikes | reg_neurons |
|----|-------|------------------|-----------------|-----------|-----------|------------------|---------------------|------------|-------------|
| 1  | 5     | 5                | 2               | 0.06      | 10        | 1                | 0.01                | 0.004      | 1e-6        |
| 2  | 15    | 3                | 8               | 0.05      | 10        | 1                | 0.02                | 0.0015     | 0           |
| 5  | 10    | 3                | 4               | 0.07      | 10        | 1.5              | 0.035               | 0.001      | 0           |
| 10 | 10    | 5                | 2               | 0.07      | 10        | 4                | 0.015               | 0.0015     | 0           |

Optimiser (all models): Adamax, lr 0.0015, betas (0.9, 0.995), batch 128, 300 epochs.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

from snncc.errors import SnnccError
from snncc.frontends.params import KEYS, PaperParams, parse_params

PRESETS: dict[int, PaperParams] = {
    1: PaperParams(scale=5, time_bin_size=5, nb_input_copies=2, tau_mem=0.06, tau_ratio=10,
                   fwd_weight_scale=1, weight_scale_factor=0.01, reg_spikes=0.004, reg_neurons=1e-6),
    2: PaperParams(scale=15, time_bin_size=3, nb_input_copies=8, tau_mem=0.05, tau_ratio=10,
                   fwd_weight_scale=1, weight_scale_factor=0.02, reg_spikes=0.0015, reg_neurons=0),
    5: PaperParams(scale=10, time_bin_size=3, nb_input_copies=4, tau_mem=0.07, tau_ratio=10,
                   fwd_weight_scale=1.5, weight_scale_factor=0.035, reg_spikes=0.001, reg_neurons=0),
    10: PaperParams(scale=10, time_bin_size=5, nb_input_copies=2, tau_mem=0.07, tau_ratio=10,
                    fwd_weight_scale=4, weight_scale_factor=0.015, reg_spikes=0.0015, reg_neurons=0),
}

THRESHOLDS = tuple(sorted(PRESETS))


@dataclass(frozen=True)
class OptimiserSettings:
    """The authors' optimiser and schedule."""

    lr: float = 0.0015
    betas: tuple[float, float] = (0.9, 0.995)
    batch_size: int = 128
    epochs: int = 300

    def as_dict(self) -> dict:
        return asdict(self)


def paper_preset(threshold: int) -> PaperParams:
    """The paper's hyper-parameters for encoding threshold ``threshold`` (1, 2, 5 or 10)."""
    if threshold not in PRESETS:
        raise SnnccError(f"no paper preset for threshold {threshold} (known: 1, 2, 5, 10)", field="threshold")
    return PRESETS[threshold]


def with_overrides(params: PaperParams, overrides: dict[str, str | float]) -> PaperParams:
    """``params`` with some keys replaced; values are validated by the parameters-file rules."""
    for key in overrides:
        if key not in KEYS:
            raise SnnccError(f"unknown hyper-parameter (expected one of {', '.join(KEYS)})", field=key)
    merged = {**params.as_dict(), **overrides}
    text = "".join(f"{k} {merged[k]}\n" for k in KEYS)
    return parse_params(text, source="--set")


def parse_overrides(items: list[str] | None) -> dict[str, str]:
    """``["tau_mem=0.05", ...]`` -> ``{"tau_mem": "0.05"}``."""
    out: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise SnnccError("must be KEY=VALUE", field=f"--set {item}")
        out[key.strip()] = value.strip()
    return out


__all__ = ["PRESETS", "THRESHOLDS", "OptimiserSettings", "paper_preset", "with_overrides", "parse_overrides", "replace"]
