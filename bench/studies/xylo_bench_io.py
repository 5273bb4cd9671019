"""What the Xylo benches share: the model they measure and where their results go.

    model_arguments(ap)   --model (default: the NIR paper's subtract-reset Braille RSNN), --dt, --reset, --samples,
                          --steps, --density
    load(args)            the model; a NIR graph stores no dt and no reset, so they default to 1e-4 and subtract
                          there, while snncc's IR states both (--dt, --reset then stay unset)
    write_result(p, r)    ``r`` as indented JSON at ``p`` (its folder made), and the line that says so
    agreement(c, ref)     the one agreement rule (``snncc.targets.kit.agreement``) of counts ``c`` with the float
                          graph's ``ref``, with the count correlation beside it
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
BRAILLE = ROOT / "tests" / "data" / "nir" / "braille_noDelay_noBias_subtract.nir"


def model_arguments(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--model", default=str(BRAILLE))
    ap.add_argument("--dt", type=float, default=None, help="NIR only (default 1e-4)")
    ap.add_argument("--reset", default=None, help="NIR only (default subtract)")
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--steps", type=int, default=256)
    ap.add_argument("--density", type=float, default=0.08)


def load(args: argparse.Namespace):
    from snncc.frontends import LoadOptions, load_model

    nir = Path(args.model).suffix == ".nir"
    dt = args.dt if args.dt is not None or not nir else 1e-4
    reset = args.reset if args.reset is not None or not nir else "subtract"
    return load_model(Path(args.model), LoadOptions(dt=dt, reset=reset))


def write_result(path: str | Path, result: dict[str, Any]) -> None:
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1))
    print(f"wrote {out}")


@dataclass
class Agreement:
    """``kit.agreement.argmax_agreement`` of a run with the float graph (``argmax``) and the count correlation."""

    argmax: Any                       # snncc.targets.kit.agreement.ArgmaxAgreement
    count_correlation: float | None

    @property
    def share(self) -> float | None:
        return self.argmax.share

    @property
    def decided(self) -> int:
        return self.argmax.decided

    def as_dict(self) -> dict[str, Any]:
        return {**self.argmax.as_dict(), "count_correlation": self.count_correlation}

    def line(self) -> str:
        corr = "undefined" if self.count_correlation is None else f"{self.count_correlation:.3f}"
        return f"{self.argmax.text()}, count correlation {corr}"


def agreement(counts, reference) -> Agreement:
    """``counts`` (B, classes) against the float graph's ``reference`` counts by the one agreement rule."""
    from snncc.targets.kit.agreement import argmax_agreement, count_correlation

    return Agreement(argmax_agreement(reference, counts), count_correlation(counts, reference))
