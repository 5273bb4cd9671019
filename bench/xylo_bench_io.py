"""What the Xylo benches share: the model they measure and where their results go.

    model_arguments(ap)   --model (default: the NIR paper's subtract-reset Braille RSNN), --dt, --reset, --samples,
                          --steps, --density
    load(args)            the model; a NIR graph stores no dt and no reset, so they default to 1e-4 and subtract
                          there, while snncc's IR states both (--dt, --reset then stay unset)
    write_result(p, r)    ``r`` as indented JSON at ``p`` (its folder made), and the line that says so
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
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
