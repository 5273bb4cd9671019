"""Small seeded models (20 hidden, 30 steps) and inputs for the Jetson tests."""

from __future__ import annotations

import numpy as np
import torch

from snncc.models.lstm import LSTMClassifier, LSTMConfig
from snncc.models.snn import SNNConfig, SpikingClassifier

STEPS = 30


def active_snn(recurrent: bool, order: str, copies: int, seed: int) -> SpikingClassifier:
    """A small SNN whose weights are scaled up so that the hidden and output layers spike."""
    torch.manual_seed(seed)
    m = SpikingClassifier(SNNConfig(n_inputs=6, n_hidden=20, n_outputs=5, input_copies=copies,
                                    recurrent=recurrent, order=order))
    with torch.no_grad():
        m.w_in.mul_(8.0)
        m.w_out.mul_(8.0)
        if m.v_rec is not None:
            m.v_rec.mul_(60.0)
    return m


MODELS = {
    "rsnn": lambda: active_snn(True, "spytorch", 2, 0),
    "ffsnn": lambda: active_snn(False, "loihi", 1, 1),
    "lstm": lambda: (torch.manual_seed(2), LSTMClassifier(LSTMConfig(n_inputs=12, n_hidden=20, n_outputs=5)))[1],
    "elstm": lambda: (torch.manual_seed(3), LSTMClassifier(LSTMConfig(n_inputs=6, n_hidden=20, n_outputs=5,
                                                                      signal="spikes")))[1],
}


def seeded_events(batch: int, steps: int, channels: int, seed: int, rate: float = 0.2) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return (rng.random((batch, steps, channels)) < rate).astype(np.float32)


def seeded_inputs(graph, batch: int, steps: int, seed: int) -> np.ndarray:
    channels = graph.metadata.get("base_inputs") or graph.node("input").width
    if graph.node("input").signal == "spikes":
        return seeded_events(batch, steps, channels, seed)
    return np.random.default_rng(seed).standard_normal((batch, steps, channels)).astype(np.float32)
