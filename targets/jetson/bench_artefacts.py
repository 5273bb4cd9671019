"""``snncc bench``'s work: the paper's protocol (``bench_protocol.py``) on one artefact (with INA3221 power),
or on several side by side; inputs from a data set or seeded synthetic inputs of the artefact's shape."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from snncc.targets.kit import SnnccError


def synthetic_inputs(manifest: dict, samples: int, seed: int) -> np.ndarray:
    """Seeded random inputs of the artefact's shape (events at 10 %, or N(0, 1) frames)."""
    rng = np.random.default_rng(seed)
    shape = (samples, manifest["time_steps"], manifest["input"]["channels"])
    if manifest["input"]["signal"] == "spikes":
        return (rng.random(shape) < 0.1).astype(np.float32)
    return rng.standard_normal(shape).astype(np.float32)


def _data_label(data: Path, meta: dict, n: int) -> str:
    return f"{data} ({'SYNTHETIC' if meta.get('synthetic') else 'recorded'} data, {n} samples)"


def bench_one(artefact: Path, *, data: Path | None = None, samples: int = 64, power: bool = False,
              power_root: Path = Path("/"), rail: str = "VDD_IN", repeats: int = 3, warmup_passes: int = 6,
              timed_passes: int = 6, stream: bool = False, backend: str = "auto",
              progress: Callable[[int, int, str], None] | None = None):
    """``BenchRecord`` of one artefact; ``progress(samples_done, total, phase)`` as the protocol goes."""
    from snncc.targets.jetson.bench_protocol import run_protocol
    from snncc.targets.jetson.power import PowerSampler
    from snncc.targets.jetson.run_artefact import open_runner
    from snncc.targets.jetson.standalone_runner import RunnerError

    runner = open_runner(artefact, backend, "step" if stream else "sequence")
    labels = None
    if data is not None:
        from snncc.targets.kit.inputs import load_dataset

        inputs, labels, meta = load_dataset(data)
        label = _data_label(data, meta, len(labels))
    else:
        inputs = synthetic_inputs(runner.manifest, samples, seed=0)
        label = f"SYNTHETIC inputs (seeded random, {samples} samples, seed 0): latency only, no accuracy"
    sampler = PowerSampler(root=str(power_root), rail_name=rail) if power else None
    n = len(inputs)
    total = warmup_passes * n + timed_passes * n * repeats
    done = [0]

    def tick(phase: str, k: int) -> None:
        done[0] += k
        if progress is not None:
            progress(done[0], total, phase)

    try:
        record = run_protocol(runner, inputs, labels, data_label=label, warmup_passes=warmup_passes,
                              timed_passes=timed_passes, repeats=repeats, stream=stream, sampler=sampler,
                              progress=tick)
    except RunnerError as ex:
        raise SnnccError(ex.rule, file=str(data or artefact), field=ex.field) from None
    if not power:
        record.notes.append("power not sampled (use --power on a Jetson)")
    return record


def bench_many(artefacts: list[Path], *, data: Path | None = None, samples: int = 64, repeats: int = 3,
               warmup_passes: int = 6, timed_passes: int = 6, stream: bool = False, backend: str = "auto",
               progress: Callable[[int, int, str], None] | None = None):
    """``LatencyComparison`` of several artefacts with the same protocol; each takes ``data`` when its
    channels (and, for a fixed time axis, its steps) fit, else seeded SYNTHETIC inputs.
    ``progress(samples_done, total, "<artefact>: <phase>")`` over every artefact's protocol."""
    from snncc.targets.jetson.bench_protocol import compare_protocol
    from snncc.targets.jetson.run_artefact import open_runner
    from snncc.targets.jetson.standalone_runner import RunnerError

    loaded = None
    if data is not None:
        from snncc.targets.kit.inputs import load_dataset

        loaded = load_dataset(data)
    entries = []
    for artefact in artefacts:
        runner = open_runner(artefact, backend, "step" if stream else "sequence")
        channels = runner.manifest["input"]["channels"]
        if loaded is not None and loaded[0].shape[2] == channels and (
                runner.manifest["time_axis"] == "dynamic" or loaded[0].shape[1] == runner.manifest["time_steps"]):
            inputs, labels = loaded[0], loaded[1]
            label = _data_label(data, loaded[2], len(labels))
        else:
            inputs, labels = synthetic_inputs(runner.manifest, samples, seed=0), None
            label = f"SYNTHETIC inputs (seeded random, {samples} samples, seed 0): latency only"
        entries.append((runner, inputs, labels, label))
    total = sum((warmup_passes + timed_passes * repeats) * len(inputs) for _, inputs, _, _ in entries)
    done = [0]

    def tick(phase: str, k: int) -> None:
        done[0] += k
        if progress is not None:
            progress(done[0], total, phase)

    try:
        return compare_protocol(entries, progress=tick, warmup_passes=warmup_passes, timed_passes=timed_passes,
                                repeats=repeats, stream=stream)
    except RunnerError as ex:
        raise SnnccError(ex.rule, file=str(data or artefacts[0]), field=ex.field) from None
