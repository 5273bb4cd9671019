"""Optimiser and schedule of the time-series classifiers, where the paper is silent.

The paper gives 300 epochs, an 80/20 split and three runs for these models, nothing more; the
rest is what the family's reference code (Ismail Fawaz et al., dl-4-tsc / InceptionTime) uses:

| model     | optimiser | lr    | batch | schedule                                             | loss              |
|-----------|-----------|-------|-------|------------------------------------------------------|-------------------|
| FCN       | Adam      | 1e-3  | 16    | ReduceLROnPlateau(train loss, x0.5, 50 ep, >= 1e-4)  | cross-entropy     |
| ResNet    | Adam      | 1e-3  | 64    | same                                                 | cross-entropy     |
| Inception | Adam      | 1e-3  | 64    | same                                                 | cross-entropy     |
| Encoder   | Adam      | 1e-5  | 12    | none                                                 | cross-entropy     |
| TCNN      | Adam      | 1e-3  | 16    | none                                                 | MSE, sigmoid out  |

Adam's betas are its defaults (0.9, 0.999). The family trains 100-2000 epochs; ``snncc train``
defaults to the paper's 300.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class FamilySchedule:
    optimiser: str
    lr: float
    batch_size: int
    plateau: tuple | None          # (factor, patience in epochs, min_lr) on the training loss
    loss: str = "cross_entropy"
    betas: tuple = (0.9, 0.999)
    family_epochs: int = 0         # what the family's code runs (the paper: 300)
    source: str = "the time-series family's reference code (paper silent)"

    def as_dict(self) -> dict:
        return asdict(self)


PLATEAU = (0.5, 50, 1e-4)
FAMILY: dict[str, FamilySchedule] = {
    "fcn": FamilySchedule("adam", 1e-3, 16, PLATEAU, family_epochs=2000),
    "resnet": FamilySchedule("adam", 1e-3, 64, PLATEAU, family_epochs=1500),
    "inception": FamilySchedule("adam", 1e-3, 64, PLATEAU, family_epochs=1500),
    "encoder": FamilySchedule("adam", 1e-5, 12, None, family_epochs=100),
    "tcnn": FamilySchedule("adam", 1e-3, 16, None, loss="mse_sigmoid", family_epochs=2000),
}
