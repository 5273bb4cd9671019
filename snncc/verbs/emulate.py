"""``snncc emulate``: run a written artefact in its target's emulator (or a model file in the IR reference), save it.

X.npy: 0/1 spikes (bool, uint8 or float) shaped (T, C) or (B, T, C), C = the bundle's input width, or in
the model's own shape: the data's channels when the bundle takes input copies (tiled by snncc), frames
(B, T, C, H, W) of a convolutional model (flattened); the record says what was done.
OUT.npz: output_spikes (B, T, n_out) uint8, counts (B, n_out), prediction (B,), overflow counts;
with record="all" also layer{i}_spikes, layer{i}_voltage, layer{i}_current for every layer i
(the model's units only: always-on bias sources are left out).
When compile shifted the outputs (timing, current biases), an input of the model's length
tSample - output_shift gets output_shift blank steps appended, so every output step is seen.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.errors import SnnccError, one_line
from snncc.verbs import VerbProgress, counting

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.targets.base import Emulation


@dataclass
class EmulateRecord:
    bundle: str
    output: str
    stream: bool
    emulation: Emulation     # the target's emulation (``snncc.targets.base.Emulation``)
    target: str = ""

    def as_dict(self) -> dict[str, object]:
        e = self.emulation
        return {"bundle": self.bundle, "target": self.target, "output": self.output, "samples": e.samples,
                "steps": e.steps, "mode": "stream" if self.stream else "batch", "prediction": e.prediction,
                **dict(e.summary())}

    def warnings(self) -> list[str]:
        """What the user should know but is not the result (the CLI prints it on stderr)."""
        return list(self.emulation.warnings())

    def render_text(self, console: Console) -> None:
        e = self.emulation
        for line in e.lines():
            console.print(line, markup=False, soft_wrap=True)
        prediction = e.prediction
        console.print(f"emulated {e.samples} sample(s) x {e.steps} steps ({'stream' if self.stream else 'batch'} "
                      f"mode); predictions {prediction[:20].tolist()}{' ...' if e.samples > 20 else ''}",
                      markup=False)
        console.print(f"wrote {one_line(self.output)}", markup=False)


def emulate_bundle(bundle: str | Path, *, input: str | Path, output: str | Path, target: str | None = None,
                   record: str = "outputs", stream: bool = False, gap: int | None = None,
                   params: str | Path | None = None, dt: float | None = None, reset: str | None = None,
                   progress: VerbProgress | None = None) -> EmulateRecord:
    """Emulate ``bundle`` on the spikes in ``input`` (.npy) and write the results to ``output`` (.npz,
    atomically). ``bundle`` is a written artefact (its target's emulator; ``stream``: one continuous run with
    ``gap`` blank steps, default 100, between samples) or a model file (the float graph run by the IR reference,
    loaded with the model options ``params``, ``dt``, ``reset``: ``snncc.verbs.float_run``)."""
    from snncc.artefacts import recognised, target_for
    from snncc.atomic import write_npz_atomic
    from snncc.inputs import load_array
    from snncc.targets import capability

    if record not in ("outputs", "all"):
        raise SnnccError("must be 'outputs' or 'all'", field="--record")
    from snncc.atomic import check_destination

    check_destination(output)            # an input named as the output is refused first, as for every writer
    if Path(output).suffix.lower() != ".npz":
        raise SnnccError("the results are an .npz (several arrays): name the file .npz", file=str(output), field="--output")
    path = Path(bundle)
    model_options = {"--params": params, "--dt": dt, "--reset": reset}
    if target is not None or recognised(path) or not path.is_file():
        tgt = target_for(path, target, "emulate")
        given = next((flag for flag, value in model_options.items() if value is not None), None)
        if given is not None:
            raise SnnccError("applies to a model file, not to a written artefact (compile fixed the model)",
                             field=given)
        emulate = capability(tgt, "emulate")
        x = load_array(input)
        total = int(x.shape[0]) if x.ndim in (3, 5) else 1   # (B, T, C) or (B, T, C, H, W) frames
        emulation = emulate(path, x, record=record, stream=stream, gap=gap, source=str(input),
                            progress=counting(progress, total, "emulating"))
        name = getattr(tgt, "name", "")
    else:
        emulation = _float_emulation(path, input, record, stream, params, dt, reset, progress)
        name = "float"
    write_npz_atomic(output, dict(emulation.arrays()))      # zlib level 1: numpy's level 6 took longer than the emulation
    return EmulateRecord(str(bundle), str(output), stream, emulation, name)


def _float_emulation(path: Path, input: str | Path, record: str, stream: bool, params: str | Path | None,
                     dt: float | None, reset: str | None, progress: VerbProgress | None) -> Emulation:
    from snncc.frontends import LoadOptions, load_model
    from snncc.inputs import load_array
    from snncc.verbs.float_run import run_float

    if stream:
        raise SnnccError("applies to a target's emulator; the float graph runs each sample from rest", field="--stream")
    graph = load_model(path, LoadOptions(params=None if params is None else Path(params), dt=dt, reset=reset))
    x = load_array(input)
    total = int(x.shape[0]) if x.ndim in (3, 5) else 1
    found: Emulation = run_float(graph, x, record=record, source=str(input),
                                 progress=counting(progress, total, "running the float graph"))
    return found
