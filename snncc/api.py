"""snncc's Python API: every CLI verb as a function with the same name and typed arguments.

Each function returns a record with ``as_dict()`` (what ``--json`` prints) and
``render_text(console)`` (what the CLI prints); the CLI only parses options, calls the function
and prints the record. Names are resolved on first use, so ``import snncc.api`` is instant and a
verb imports only what it needs. ``docs/api.md`` shows the Python equivalent of each command.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Callable

if TYPE_CHECKING:   # what type checkers see: the functions themselves, with their signatures
    from snncc.verbs.analyse_ttc import analyse_ttc
    from snncc.verbs.bench import bench_artefacts as bench
    from snncc.verbs.check import check_model as check
    from snncc.verbs.compare import compare_model as compare
    from snncc.verbs.compile import compile_model as compile
    from snncc.verbs.data_analyse import data_analyse
    from snncc.verbs.data_encode import data_encode
    from snncc.verbs.data_nir import data_nir
    from snncc.verbs.data_frames import data_frames
    from snncc.verbs.data_synth import data_synth
    from snncc.verbs.emulate import emulate_bundle as emulate
    from snncc.verbs.export import export
    from snncc.verbs.hpo import hpo_report, hpo_run, hpo_space
    from snncc.verbs.inspect import inspect
    from snncc.verbs.map import map_cores as map
    from snncc.verbs.report import report_energy as report
    from snncc.verbs.run import run_artefact as run
    from snncc.verbs.train import train

# public name -> "module:attribute" that defines it (verb names follow the CLI: ``compile``,
# ``check``, ``data_encode`` for ``snncc data encode``, ...)

# --- target verbs: compile, check, compare, emulate, map, report, run, bench ---
_TARGET_HOMES: dict[str, str] = {
    "compile": "snncc.verbs.compile:compile_model",
    "check": "snncc.verbs.check:check_model",
    "compare": "snncc.verbs.compare:compare_model",
    "emulate": "snncc.verbs.emulate:emulate_bundle",
    "map": "snncc.verbs.map:map_cores",
    "report": "snncc.verbs.report:report_energy",
    "run": "snncc.verbs.run:run_artefact",
    "bench": "snncc.verbs.bench:bench_artefacts",
}

# --- model and data verbs: inspect, export, data, train, analyse, hpo ---
_MODEL_DATA_HOMES: dict[str, str] = {
    "inspect": "snncc.verbs.inspect:inspect",
    "export": "snncc.verbs.export:export",
    "data_synth": "snncc.verbs.data_synth:data_synth",
    "data_encode": "snncc.verbs.data_encode:data_encode",
    "data_nir": "snncc.verbs.data_nir:data_nir",
    "data_frames": "snncc.verbs.data_frames:data_frames",
    "data_analyse": "snncc.verbs.data_analyse:data_analyse",
    "train": "snncc.verbs.train:train",
    "analyse_ttc": "snncc.verbs.analyse_ttc:analyse_ttc",
    "hpo_run": "snncc.verbs.hpo:hpo_run",
    "hpo_report": "snncc.verbs.hpo:hpo_report",
    "hpo_space": "snncc.verbs.hpo:hpo_space",
}

_HOMES = {**_TARGET_HOMES, **_MODEL_DATA_HOMES}

__all__ = sorted(_HOMES)


def __getattr__(name: str) -> Callable[..., object]:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'snncc.api' has no attribute {name!r}")
    module, _, attribute = home.partition(":")
    found: Callable[..., object] = getattr(importlib.import_module(module), attribute or name)
    return found


def __dir__() -> list[str]:
    return __all__
