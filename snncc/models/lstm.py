"""The paper's LSTM baselines: frames (12 -> 228 -> 27) and events (eLSTM, 24 -> 228 -> 27).

One bias vector per gate, as the paper counts parameters (225,975 / 236,919): ``nn.LSTM``'s
second bias (``bias_hh_l0``) is held at zero and not trained. The class is decided from the
dense layer applied to the last hidden state.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import torch
from torch import nn


@dataclass
class LSTMConfig:
    n_inputs: int = 12          # 12 taxels (frames) or 24 event channels (eLSTM)
    n_hidden: int = 228
    n_outputs: int = 27
    dt: float = 0.025           # s per frame (40 Hz) or per event bin
    signal: str = "analog"      # "analog" frames or "spikes" events

    @property
    def kind(self) -> str:
        return "elstm" if self.signal == "spikes" else "lstm"


class LSTMClassifier(nn.Module):
    def __init__(self, config: LSTMConfig | None = None, **overrides):
        super().__init__()
        cfg = config or LSTMConfig()
        if overrides:
            cfg = LSTMConfig(**{**asdict(cfg), **overrides})
        self.config = cfg
        self.lstm = nn.LSTM(cfg.n_inputs, cfg.n_hidden, batch_first=True)
        with torch.no_grad():
            self.lstm.bias_hh_l0.zero_()
        self.lstm.bias_hh_l0.requires_grad_(False)
        self.fc = nn.Linear(cfg.n_hidden, cfg.n_outputs)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """(B, T, n_inputs) -> class scores (B, n_outputs) from the last hidden state."""
        out, _ = self.lstm(x.to(self.fc.weight.dtype))
        return self.fc(out[:, -1])

    def architecture(self) -> dict:
        return {"kind": self.config.kind, **asdict(self.config)}


def count_trainable(module: nn.Module) -> int:
    return sum(p.numel() for p in module.parameters() if p.requires_grad)
