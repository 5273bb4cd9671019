"""The paper's standard time-series classifiers on frames: FCN, ResNet, Encoder, Time-CNN, Inception.

Written after the descriptions of the Keras family the authors used (Ismail Fawaz et al.,
"dl-4-tsc" / InceptionTime): Keras 'same' padding (extra pad on the right for even kernels),
Keras' BatchNorm epsilon (1e-3; momentum torch's 0.1, as Keras' 0.99 needs very long runs to
settle), softmax/sigmoid left to the loss.
Input (B, T, C) frames as the LSTM takes them (12 taxels, T = 54 frames of 25 ms), output class
scores (B, n_outputs); the data are buffered: the whole sample is needed before a prediction.

Parameter counts on 12 taxels x 54 frames, 27 classes (``count_trainable`` / ``keras_total``,
the latter adding BatchNorm's running mean and variance, as Keras' "Total params" does):

=========  ===========  ===========  =====================================================
model      trainable    Keras total  paper
=========  ===========  ===========  =====================================================
FCN          279,451      280,475    280k  (both round to it)
ResNet       513,819      516,379    516k  = Keras total (trainable would read 514k)
Inception    452,251      454,299    452k  = trainable, with kernels 36/18/9 (see below)
Encoder    3,280,411    3,280,411    "one order of magnitude" above FCN (11.7x)
TCNN           2,997        2,997    2,673 needs a pooled length of 5 (see below)
=========  ===========  ===========  =====================================================

Inception: the family's default longest kernel is 40 (kernels 40/20/10), which gives 495,259
trainable parameters; the paper's 452k is reproduced (452,251) only by a longest kernel of 36
(kernels 36/18/9), which is therefore this zoo's default (``longest_kernel``); the paper does
not state its kernel sizes, so this is an inference from the count.
TCNN: 2,673 = 510 + 516 + (12 x 5) x 27 + 27, i.e. the flattened map holds 5 steps; 54 frames
through two average-poolings of 3 leave 6 (54 -> 18 -> 6), giving 2,997. The paper's count
corresponds to 45-53 input frames; with the 54-frame input the count cannot be matched without
changing the architecture, so the zoo keeps the architecture (tested: ``n_steps=50`` gives 2,673).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import torch
from torch import nn
from torch.nn import functional as F

BASELINE_KINDS = ("fcn", "resnet", "encoder", "tcnn", "inception")
KERAS_BN = {"eps": 1e-3}   # Keras epsilon; momentum torch's 0.1 (Keras 0.99 needs long runs to settle)


@dataclass
class BaselineConfig:
    kind: str = "fcn"
    n_inputs: int = 12          # taxels
    n_steps: int = 54           # frames (Encoder and TCNN flatten time, so T is part of the model)
    n_outputs: int = 27
    dt: float = 0.025           # s per frame (40 Hz)
    longest_kernel: int = 36    # Inception only: kernels k, k//2, k//4

    def __post_init__(self):
        if self.kind not in BASELINE_KINDS:
            raise ValueError(f"unknown baseline kind {self.kind!r}")
        if self.n_steps < 9 or self.n_inputs < 1 or self.n_outputs < 2 or self.longest_kernel < 4:
            raise ValueError("needs n_steps >= 9, n_inputs >= 1, n_outputs >= 2, longest_kernel >= 4")


class SameConv1d(nn.Module):
    """Conv1d with Keras 'same' padding: left (k-1)//2, right k//2 (explicit, so ONNX sees a Pad)."""

    def __init__(self, c_in: int, c_out: int, k: int, bias: bool = True):
        super().__init__()
        self.pad = ((k - 1) // 2, k // 2)
        self.conv = nn.Conv1d(c_in, c_out, k, bias=bias)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.conv(F.pad(x, self.pad) if any(self.pad) else x)


def conv_bn(c_in: int, c_out: int, k: int, relu: bool = True, bias: bool = True) -> nn.Sequential:
    layers = [SameConv1d(c_in, c_out, k, bias=bias), nn.BatchNorm1d(c_out, **KERAS_BN)]
    return nn.Sequential(*layers, nn.ReLU()) if relu else nn.Sequential(*layers)


class FCN(nn.Module):
    """conv(128, 8) -> conv(256, 5) -> conv(128, 3), each BN + ReLU; global average pool; dense."""

    def __init__(self, cfg: BaselineConfig):
        super().__init__()
        self.body = nn.Sequential(conv_bn(cfg.n_inputs, 128, 8), conv_bn(128, 256, 5), conv_bn(256, 128, 3))
        self.fc = nn.Linear(128, cfg.n_outputs)

    def forward(self, x: torch.Tensor) -> torch.Tensor:   # x: (B, C, T)
        return self.fc(self.body(x).mean(dim=2))


class ResidualBlock(nn.Module):
    """Three conv-BN (8, 5, 3) with ReLU between; shortcut 1x1 conv + BN (BN alone when widths match)."""

    def __init__(self, c_in: int, c_out: int):
        super().__init__()
        self.body = nn.Sequential(conv_bn(c_in, c_out, 8), conv_bn(c_out, c_out, 5), conv_bn(c_out, c_out, 3, relu=False))
        self.shortcut = conv_bn(c_in, c_out, 1, relu=False) if c_in != c_out else nn.BatchNorm1d(c_out, **KERAS_BN)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return F.relu(self.body(x) + self.shortcut(x))


class ResNet(nn.Module):
    """Three residual blocks of 64, 128, 128 maps; global average pool; dense."""

    def __init__(self, cfg: BaselineConfig):
        super().__init__()
        self.body = nn.Sequential(ResidualBlock(cfg.n_inputs, 64), ResidualBlock(64, 128), ResidualBlock(128, 128))
        self.fc = nn.Linear(128, cfg.n_outputs)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.fc(self.body(x).mean(dim=2))


class EncoderStage(nn.Module):
    """conv -> instance norm (per-channel affine) -> PReLU (one slope per channel) -> dropout 0.2."""

    def __init__(self, c_in: int, c_out: int, k: int):
        super().__init__()
        self.conv = SameConv1d(c_in, c_out, k)
        self.norm = nn.InstanceNorm1d(c_out, affine=True, eps=1e-3)
        self.act = nn.PReLU(c_out)
        self.drop = nn.Dropout(0.2)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.drop(self.act(self.norm(self.conv(x))))


class Encoder(nn.Module):
    """Encoder (Serrà et al.): stages (128, 5), (256, 11) with max-pool 2, (512, 21); attention:
    half the maps weighted by the softmax (over maps, as the family's code does) of the other
    half; dense 256 (sigmoid) per step + instance norm; flatten; dense."""

    def __init__(self, cfg: BaselineConfig):
        super().__init__()
        self.stages = nn.ModuleList([EncoderStage(cfg.n_inputs, 128, 5), EncoderStage(128, 256, 11),
                                     EncoderStage(256, 512, 21)])
        self.step_dense = nn.Linear(256, 256)
        self.norm = nn.InstanceNorm1d(256, affine=True, eps=1e-3)
        self.fc = nn.Linear(256 * (cfg.n_steps // 4), cfg.n_outputs)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = F.max_pool1d(self.stages[0](x), 2)
        x = F.max_pool1d(self.stages[1](x), 2)
        x = self.stages[2](x)
        data, weight = x[:, :256], torch.softmax(x[:, 256:], dim=1)
        y = torch.sigmoid(self.step_dense((data * weight).transpose(1, 2))).transpose(1, 2)
        return self.fc(torch.flatten(self.norm(y), 1))


class TimeCNN(nn.Module):
    """Time-CNN (Zhao et al.): conv(6, 7) sigmoid -> avg-pool 3 -> conv(12, 7) sigmoid -> avg-pool 3
    -> flatten -> dense (sigmoid outputs, trained with MSE on one-hot labels). Padding 'same' for
    T < 60, else 'valid' (the family's rule)."""

    def __init__(self, cfg: BaselineConfig):
        super().__init__()
        same = cfg.n_steps < 60
        self.conv1 = SameConv1d(cfg.n_inputs, 6, 7) if same else nn.Conv1d(cfg.n_inputs, 6, 7)
        self.conv2 = SameConv1d(6, 12, 7) if same else nn.Conv1d(6, 12, 7)
        length = cfg.n_steps if same else cfg.n_steps - 6
        length = length // 3 if same else (length // 3 - 6)
        self.fc = nn.Linear(12 * (length // 3), cfg.n_outputs)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = F.avg_pool1d(torch.sigmoid(self.conv1(x)), 3)
        x = F.avg_pool1d(torch.sigmoid(self.conv2(x)), 3)
        return self.fc(torch.flatten(x, 1))


class InceptionModule(nn.Module):
    """Bottleneck 1x1 (32, when C > 1) -> convs k, k/2, k/4 (32 each, no bias) || max-pool 3 -> 1x1 (32);
    concat (128) -> BN -> ReLU."""

    def __init__(self, c_in: int, longest_kernel: int, filters: int = 32, bottleneck: int = 32):
        super().__init__()
        self.bottleneck = nn.Conv1d(c_in, bottleneck, 1, bias=False) if c_in > 1 else None
        width = bottleneck if c_in > 1 else c_in
        self.branches = nn.ModuleList(SameConv1d(width, filters, longest_kernel // 2 ** i, bias=False) for i in range(3))
        self.pool_conv = nn.Conv1d(c_in, filters, 1, bias=False)
        self.bn = nn.BatchNorm1d(4 * filters, **KERAS_BN)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        z = self.bottleneck(x) if self.bottleneck is not None else x
        pooled = F.max_pool1d(F.pad(x, (1, 1), value=float("-inf")), 3, stride=1)
        y = torch.cat([b(z) for b in self.branches] + [self.pool_conv(pooled)], dim=1)
        return F.relu(self.bn(y))


class Inception(nn.Module):
    """InceptionTime network: 6 modules, a residual shortcut (1x1 conv + BN) every 3; GAP; dense."""

    def __init__(self, cfg: BaselineConfig, depth: int = 6):
        super().__init__()
        self.modules_ = nn.ModuleList(InceptionModule(cfg.n_inputs if d == 0 else 128, cfg.longest_kernel)
                                      for d in range(depth))
        self.shortcuts = nn.ModuleList(conv_bn(cfg.n_inputs if d == 2 else 128, 128, 1, relu=False, bias=False)
                                       for d in range(depth) if d % 3 == 2)
        self.fc = nn.Linear(128, cfg.n_outputs)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        residual, shortcuts = x, iter(self.shortcuts)
        for d, module in enumerate(self.modules_):
            x = module(x)
            if d % 3 == 2:
                x = F.relu(x + next(shortcuts)(residual))
                residual = x
        return self.fc(x.mean(dim=2))


NETWORKS = {"fcn": FCN, "resnet": ResNet, "encoder": Encoder, "tcnn": TimeCNN, "inception": Inception}


class BufferedClassifier(nn.Module):
    """A zoo wrapper: frames (B, T, C) -> class scores (B, n_outputs), whichever network ``kind`` names."""

    def __init__(self, config: BaselineConfig | None = None, **overrides):
        super().__init__()
        cfg = config or BaselineConfig()
        if overrides:
            cfg = BaselineConfig(**{**asdict(cfg), **overrides})
        self.config = cfg
        self.net = NETWORKS[cfg.kind](cfg)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net(x.to(self.net.fc.weight.dtype).transpose(1, 2))

    def architecture(self) -> dict:
        return asdict(self.config)


def keras_total(module: nn.Module) -> int:
    """Trainable parameters + BatchNorm running mean and variance (Keras' "Total params")."""
    trainable = sum(p.numel() for p in module.parameters() if p.requires_grad)
    stats = sum(m.running_mean.numel() + m.running_var.numel() for m in module.modules()
                if isinstance(m, nn.BatchNorm1d) and m.running_mean is not None)
    return trainable + stats
