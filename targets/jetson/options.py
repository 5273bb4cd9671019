"""The Jetson target's options record (light: imported whenever the target is listed or chosen)."""

from __future__ import annotations

from dataclasses import dataclass

from snncc.targets.base import TargetOptions, option

DEFAULT_JETPACK = "4.6"


@dataclass(frozen=True)
class JetsonOptions(TargetOptions):
    """Jetson's options; ``seed`` (of the validation inputs) is a setting no flag offers."""

    jetpack: str | None = option(
        "JetPack version of the board (default 4.6); selects the ONNX opset (4.6 -> 13, 5.x/6.0 -> 17, "
        "6.1/6.2 -> 20).", capabilities=("lower",))
    time_steps: int | None = option("T of the unrolled sequence model (default: the model's recording length / dt, else snncc's 256).",
                                    minimum=1, rule="time steps must be a whole number >= 1", capabilities=("lower",))
    seed: int = 0
