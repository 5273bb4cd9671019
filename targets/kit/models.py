"""Model records other than an IR graph that a target may take (``model_kinds``): a buffered classifier (the
paper's time-series baselines), which has no IR graph and is lowered as a whole (Jetson)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from snncc.frontends.buffered import BufferedModel

if TYPE_CHECKING:
    from snncc.models.baselines import BufferedClassifier

__all__ = ["BufferedModel", "BufferedClassifier"]


def __getattr__(name: str):   # noqa: ANN202 (torch-based: loaded on use)
    if name == "BufferedClassifier":
        from snncc.models.baselines import BufferedClassifier

        return BufferedClassifier
    raise AttributeError(name)
