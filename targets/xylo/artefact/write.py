"""A lowered Xylo model (``lowering.lower.XyloLowered``) -> its artefact files (``format.XyloArtefact``).

Before anything is written, the network spec is serialised to spec.npz bytes, read back with
``XyloSpec.load_npz`` (``np.load(allow_pickle=False)``) and run in snncc's bit-exact emulator
beside the in-memory spec on seeded inputs: the file must give the same output spikes, else the
compilation fails.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.kit.artefact import model_record, sha256_bytes as sha256
from snncc.targets.kit.manifest import manifest_bytes, source_identity
from snncc.targets.kit.writing import npz_bytes
from snncc.targets.xylo.artefact.format import (
    BOARD_SCRIPT, FORMAT, FORMAT_VERSION, MANIFEST, README, SPEC, XYLOSIM_VERSION, XyloArtefact, candidate_text,
)
from snncc.targets.xylo.chip import get_chip

VALIDATION_SAMPLES = 8


def _file_runs_the_same(spec, data: bytes, n_in: int, steps: int) -> str:
    """Read ``data`` back as spec.npz and compare its emulation with the in-memory spec's."""
    from snncc.targets.xylo.emulation.emulator import emulate
    from snncc.targets.xylo.spec import XyloSpec

    with tempfile.TemporaryDirectory(prefix="snncc-xylo-") as tmp:
        path = Path(tmp) / SPEC
        path.write_bytes(data)
        back = XyloSpec.load_npz(path)
    if back != spec:
        raise SnnccError("spec.npz read back differs from the lowered spec (serialisation bug)", field=SPEC)
    x = (np.random.default_rng(0).random((VALIDATION_SAMPLES, steps, n_in)) < 0.1).astype(np.uint8)
    a, b = emulate(spec, x).output_spikes, emulate(back, x).output_spikes
    if not np.array_equal(a, b):
        raise SnnccError("spec.npz read back runs differently in the emulator (serialisation bug)", field=SPEC)
    return (f"spec.npz read back with np.load(allow_pickle=False) equals the lowered spec and gives the same output "
            f"spikes in snncc's emulator on {VALIDATION_SAMPLES} seeded samples of {steps} steps")


def build_manifest(low, spec, files: dict[str, bytes], source: str | None) -> dict[str, Any]:
    from snncc.targets.kit import SNNCC_VERSION

    chip = get_chip(low.chip)
    meta = low.trained.metadata
    record = low.record()
    chosen = low.candidates.get(low.rule, {})
    return {
        "format": FORMAT, "format_version": FORMAT_VERSION, "snncc_version": SNNCC_VERSION,
        "chip": {"key": chip.key, "name": chip.name, "part_number": chip.part_number},
        "dt": float(spec.dt),
        "network": {"inputs": spec.n_in, "hidden": spec.n_hidden, "outputs": spec.n_out,
                    "input_expansion": spec.n_ien, "output_expansion": spec.n_oen,
                    "synapses": int(sum(np.count_nonzero(w) for w in (spec.weights_in, spec.weights_rec,
                                                                       spec.weights_out)))},
        "aliases": [list(a) for a in spec.aliases],
        "feed": {"input_pad": int(low.timing.input_pad), "output_lag": int(low.timing.output_lag),
                 "rule": ("feed input_pad zero steps before a sample's T steps (and zeros after, to T + output_lag "
                          "steps in all); the model's output step t is the chip's output step t + output_lag"),
                 "sample_steps": int(low.steps), "sample_steps_rule": low.steps_rule},
        "quantization": record,
        "real_time": dict(low.real_time),
        "source": source_identity(meta, source),
        "model": model_record(low.trained),
        "validation": {
            "spec_file": "checked: " + files.pop("__validation__").decode(),
            "emulator": ("agreement with the float graph of the chosen rule in snncc's emulator on the calibration "
                         f"inputs' selection half: {candidate_text(chosen)}"),
        },
        "checked_with": {"snncc": SNNCC_VERSION, "numpy": np.__version__,
                         "emulator": f"snncc's bit-exact emulator (targets/xylo/emulation/emulator.py), equal to xylosim "
                                     f"{XYLOSIM_VERSION} spike for spike in snncc's test suite",
                         "board": "not exercised (no board, no samna here)"},
        "files": {name: sha256(data) for name, data in files.items()},
    }


def readme(manifest: dict[str, Any]) -> str:
    chip, net, feed = manifest["chip"], manifest["network"], manifest["feed"]
    return f"""# snncc Xylo artefact: {chip['name']} ({chip['part_number']})

{net['inputs']} inputs -> {net['hidden']} hidden neurons -> {net['outputs']} output neurons, dt = {manifest['dt']} s,
compiled by snncc {manifest['snncc_version']} from `{manifest['source']['file']}`.

| file | what |
|---|---|
| `{SPEC}` | the network as the keyword arguments of Rockpool's `XyloSim.from_specification` (integer arrays, no pickles; `aliases` an int32 table padded with -1, `dt` a 0-d array) |
| `{MANIFEST}` | chip, dt, aliases, how to feed the chip, the quantization record, file hashes, source model, versions |
| `{BOARD_SCRIPT}` | runs the network on a board through Rockpool and samna |

## Feeding the chip

The model's time and the chip's differ by the lowering's timing: feed {feed['input_pad']} zero step(s) before
each sample's T steps and read the model's output step t at the chip's step t + {feed['output_lag']}
(`snncc emulate ARTEFACT --target xylo --input x.npy -o out.npz` does this for you).

## In XyloSim (Rockpool)

    import numpy as np
    spec = dict(np.load("{SPEC}", allow_pickle=False))
    spec = {{k: (v.item() if v.ndim == 0 else v) for k, v in spec.items()}}
    spec["aliases"] = [[int(a) for a in row if a >= 0] for row in spec["aliases"]]
    # then: XyloSim.from_specification(**spec) of rockpool.devices.xylo.{chip['key']}
    # (Xylo IMU and Xylo Audio 3: rockpool.devices.xylo.syns63300.XyloSim)

snncc's own emulator equals XyloSim {XYLOSIM_VERSION} spike for spike on every network snncc's tests
compare (its test suite runs XyloSim as the oracle).

## On a board: NOT exercised

`{BOARD_SCRIPT}` was written for Rockpool + samna and has never run here: there is no board and samna
cannot be installed here. What differs on the board: samna's `config_from_specification` names the
hidden bias `bias_hidden` (it accepts any keyword, so `bias=` would be dropped silently), and the
Xylo Audio 2 board configuration takes `weights_out` with one row per hidden neuron (the script pads).
Rockpool 3.1's `config_from_specification` of all three chips names the hidden bias `bias_hidden`;
the padding of `weights_out` was read for Xylo Audio 2 (Xylo IMU and Xylo Audio 3 keep only the last
128 rows, so a network there must read its outputs from at most 128 hidden neurons, as snncc's design
rules require).
"""


def board_script(manifest: dict[str, Any]) -> str:
    chip = manifest["chip"]["key"]
    feed = manifest["feed"]
    return f'''#!/usr/bin/env python3
"""Run this snncc Xylo artefact on a board through Rockpool and samna.

NOT EXERCISED: written by snncc without a board and without samna (not installable where it was
written). Check each step against your Rockpool and samna versions before trusting its output.

    python {BOARD_SCRIPT} INPUT.npy OUT.npz      INPUT: (T, C) or (B, T, C) event counts
"""

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
CHIP = "{chip}"
INPUT_PAD, OUTPUT_LAG = {feed['input_pad']}, {feed['output_lag']}
DT = {manifest['dt']!r}


def board_spec():
    """spec.npz as samna's config_from_specification keywords (its names differ from XyloSim's)."""
    arrays = dict(np.load(HERE / "{SPEC}", allow_pickle=False))
    spec = {{k: (v.item() if v.ndim == 0 else v) for k, v in arrays.items()}}
    spec["aliases"] = [[int(a) for a in row if a >= 0] for row in spec["aliases"]]
    spec.pop("dt")                                   # the board's time step is its clock configuration
    spec["bias_hidden"] = spec.pop("bias")           # samna's name; a wrong keyword is dropped silently
    w_out = spec["weights_out"]                      # the board takes one row per hidden neuron
    n_hidden = spec["weights_rec"].shape[0]
    if w_out.shape[0] < n_hidden:
        pad = np.zeros((n_hidden - w_out.shape[0], w_out.shape[1]), w_out.dtype)
        spec["weights_out"] = np.concatenate([pad, w_out])
    return spec


def main(inp, out):
    import importlib

    x = np.load(inp, allow_pickle=False)
    x = x[None] if x.ndim == 2 else x
    device_module = importlib.import_module(f"rockpool.devices.xylo.{{CHIP}}")
    config, valid, message = device_module.config_from_specification(**board_spec())
    if not valid:
        sys.exit(f"samna refused the configuration: {{message}}")
    from rockpool.devices.xylo import find_xylo_hdks   # needs samna

    boards = find_xylo_hdks()[0]
    if not boards:
        sys.exit("no Xylo board found")
    module = device_module.XyloSamna(boards[0], config, dt=DT)
    spikes = []
    for sample in x:
        fed = np.concatenate([np.zeros((INPUT_PAD, sample.shape[1]), sample.dtype), sample,
                              np.zeros((max(0, OUTPUT_LAG - INPUT_PAD), sample.shape[1]), sample.dtype)])
        y, _, _ = module(fed, record=False)
        spikes.append(np.asarray(y)[OUTPUT_LAG:OUTPUT_LAG + sample.shape[0]])
        module.reset_state()
    np.savez(out, output_spikes=np.stack(spikes))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
'''


def build_artefact(low, source: str | None = None, steps: int = 64) -> XyloArtefact:
    """The artefact of ``low``: spec.npz checked by reading it back, the manifest, README and board script."""
    spec = low.xylo_spec
    data = npz_bytes(spec.npz_arrays())
    checked = _file_runs_the_same(spec, data, spec.n_in, steps)
    files: dict[str, bytes] = {SPEC: data, "__validation__": checked.encode()}
    manifest = build_manifest(low, spec, files, source)
    files[README] = readme(manifest).encode()
    files[BOARD_SCRIPT] = board_script(manifest).encode()
    manifest["files"].update({README: sha256(files[README]), BOARD_SCRIPT: sha256(files[BOARD_SCRIPT])})
    ordered = {SPEC: files[SPEC], MANIFEST: manifest_bytes(manifest), README: files[README],
               BOARD_SCRIPT: files[BOARD_SCRIPT]}
    return XyloArtefact(ordered, manifest, list(low.notes) + list(low.changes))
