"""Training losses of the paper's models.

SNN (the authors' SpyTorch code), with spike counts c = sum_t S_out[b, t, :]::

    loss = NLL(log_softmax(c), y)
         + reg_spikes  * mean_(batch, neurons) (sum_t S_hidden)
         + reg_neurons * mean_neurons ((sum_(batch, t) S_hidden)^2)

LSTM / eLSTM: cross-entropy on the class scores of the last step; the buffered classifiers:
cross-entropy on their scores, Time-CNN: MSE of sigmoid scores against one-hot labels.
Prediction of an SNN: argmax of the output spike counts, ties to the lowest index.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F


@dataclass
class LossParts:
    total: torch.Tensor
    nll: float
    reg_spikes: float
    reg_neurons: float


def snn_loss(out_spikes: torch.Tensor, hidden_spikes: torch.Tensor, labels: torch.Tensor,
             reg_spikes: float, reg_neurons: float) -> LossParts:
    """The authors' loss on output spikes (B, T, O) and hidden spikes (B, T, H)."""
    counts = out_spikes.sum(dim=1)
    nll = F.nll_loss(F.log_softmax(counts, dim=1), labels)
    l1 = reg_spikes * hidden_spikes.sum(dim=1).mean()
    l2 = reg_neurons * (hidden_spikes.sum(dim=(0, 1)) ** 2).mean()
    total = nll + l1 + l2
    return LossParts(total, float(nll.detach()), float(l1.detach()), float(l2.detach()))


def lstm_loss(scores: torch.Tensor, labels: torch.Tensor) -> LossParts:
    """Cross-entropy on class scores (B, n_classes)."""
    ce = F.cross_entropy(scores, labels)
    return LossParts(ce, float(ce.detach()), 0.0, 0.0)


def mse_sigmoid_loss(scores: torch.Tensor, labels: torch.Tensor) -> LossParts:
    """Time-CNN's loss: mean squared error of sigmoid(scores) against one-hot labels."""
    target = F.one_hot(labels, scores.shape[1]).to(scores.dtype)
    mse = F.mse_loss(torch.sigmoid(scores), target)
    return LossParts(mse, float(mse.detach()), 0.0, 0.0)


def spike_count_prediction(out_spikes: torch.Tensor) -> torch.Tensor:
    """argmax_o sum_t S_out[b, t, o]; ties go to the lowest index (torch.argmax returns the first)."""
    return torch.argmax(out_spikes.sum(dim=1), dim=1)
