"""``snncc emulate``'s work: a bundle run on 0/1 inputs in chunks, with the outputs' timing shift applied.

Inputs may come in the model's own shape (``snncc.input_layout``: frames (B, T, C, H, W) of a
convolutional model, or the data's channels when the bundle takes input copies, tiled); the
bundle's flat width is taken as it is.

When compile shifted the outputs (timing, current biases), an input of the model's length
tSample - output_shift gets output_shift blank steps appended, so every output step is seen.
Batch mode runs ``CHUNK`` samples at a time on one flattened network (the same results as one
run: samples are independent); stream mode is one continuous run.

The kernel is the C one (``ckernel.py``, built once by the system's C compiler; a warm call loads it in about a
millisecond) or, on a machine without a compiler, the numba one. Then a small batch run (at most ``STATEMENT_WORK``
weight-steps: samples x steps x the dense weight entries the statement multiplies per step, once per distinct delay;
and at most ``STATEMENT_LAYER_STEPS`` layer updates, each some twenty numpy calls) runs the chip's rules as
``emulator.reference_run`` states them in numpy instead: the same integers (every compile checks the kernel against
that statement, spikes, u, v and overflow counts), without the numba kernel's fixed cost of loading numba and its
cache (about 0.5 s CPU, against 0.1 s for one th1-sized sample in numpy). The result's summary names the
implementation that ran.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from snncc.targets.loihi.emulation.ckernel import C_KERNEL, NUMBA_KERNEL

CHUNK = 256
STATEMENT_WORK = 2e9             # the numpy statement runs a batch up to this many weight-steps
STATEMENT_LAYER_STEPS = 5_000    # and this many layer updates (steps x layers) (module docstring)
STATEMENT = "numpy statement of the chip's rules (emulator.reference_run: a small run)"


@dataclass
class BundleEmulation:
    """The emulator's result on ``inputs`` (B, T, C), and how the inputs were padded."""

    network: object          # LoihiNetwork
    result: object           # EmulationResult
    samples: int
    steps: int
    padded_steps: int        # blank steps appended for the outputs' shift
    output_shift: int
    input_note: str | None = None   # what was done to take the inputs in the model's own shape
    implementation: str = C_KERNEL  # which of the bit-exact implementations ran (module docstring)

    @property
    def prediction(self) -> np.ndarray:
        return self.result.prediction

    @property
    def overflow(self) -> dict[str, int]:
        return self.result.overflow

    @property
    def t_sample(self) -> int:
        return int(self.network.t_sample)

    def summary(self) -> dict[str, object]:
        return {"overflow": self.overflow, "padded_steps": self.padded_steps, "input_layout": self.input_note,
                "implementation": self.implementation}

    def lines(self) -> list[str]:
        out = [f"input: {self.input_note}"] if self.input_note else []
        if self.padded_steps:
            out.append(f"appended {self.padded_steps} blank step(s) to each sample: on Loihi the outputs appear "
                       f"{self.padded_steps} step(s) later than in the model (see the bundle's timing record)")
        out.append(f"overflow {self.overflow}")
        if self.implementation == STATEMENT:
            out.append("ran the numpy statement of the chip's rules (a small run; the numba kernel gives the same "
                       "integers, as every compile checks)")
        return out

    def warnings(self) -> list[str]:
        if not self.padded_steps and self.output_shift and self.steps < self.t_sample:
            return [f"the bundle's outputs appear {self.output_shift} step(s) late and the input is shorter than "
                    f"tSample ({self.t_sample}); the last output steps fall outside the run"]
        return []

    def arrays(self) -> dict[str, np.ndarray]:
        """What OUT.npz holds: outputs, counts, prediction, overflow; layer{i}_* named by HDF5 layer index
        (the model's units only: always-on bias sources are left out)."""
        res, net = self.result, self.network
        arrays = {"output_spikes": res.output_spikes, "counts": res.counts, "prediction": res.prediction,
                  "overflow_q_wrap": np.int64(res.overflow["q_wrap"]),
                  "overflow_u_wrap": np.int64(res.overflow["u_wrap"]),
                  "overflow_v_clip": np.int64(res.overflow["v_clip"])}
        index = net.metadata.get("hdf5_layer_index") or list(range(len(net.layers)))
        for field_name, records in (("spikes", res.spikes), ("voltage", res.voltage), ("current", res.current)):
            for i, a in records.items():   # a SLAYER flatten layer has no state
                arrays[f"layer{index[i]}_{field_name}"] = a[..., :net.layers[i].model_n]
        return arrays


def emulate_bundle(network, inputs, *, record: str = "outputs", stream: bool = False, gap: int | None = None,
                   source: str | None = None, progress: Callable[[int], None] | None = None) -> BundleEmulation:
    """Check ``inputs`` against the bundle's width, pad for the output shift, emulate; ``progress(n)``
    after each chunk of n samples (batch mode)."""
    from snncc.targets.kit.inputs import InputLayout, to_artefact_layout
    from snncc.targets.kit import SnnccError
    from snncc.targets.loihi.emulation.emulator import RECORD_CHOICES, PreparedNetwork, check_inputs, pad, reference_run
    from snncc.targets.loihi.emulation.flat import kernel_name

    inputs, note = to_artefact_layout(inputs, InputLayout.from_record(network.input_width, network.metadata))
    x = check_inputs(inputs, network.input_width, source=source)
    shift = int(network.metadata.get("output_shift", 0) or 0)
    padded = shift if shift and x.shape[1] + shift == network.t_sample else 0
    x = pad(x, padded)
    if record not in RECORD_CHOICES:
        raise SnnccError(f"record must be one of {RECORD_CHOICES}", field="record")
    prepared = PreparedNetwork(network)          # flattened once for every chunk
    implementation = kernel_name(prepared.flat)
    if stream:
        result = prepared.run(x, record=record, mode="stream", gap=gap)
    elif gap is None and implementation == NUMBA_KERNEL and small(network, *x.shape[:2]):
        # (a --gap in batch mode: the kernel path refuses it)
        PreparedNetwork.check_size(network, x.shape[0] * x.shape[1], record)
        result, implementation = reference_run(network, x, record=record), STATEMENT
        if progress is not None:
            progress(x.shape[0])
    else:
        parts = []
        for start in range(0, x.shape[0], CHUNK):
            parts.append(prepared.run(x[start:start + CHUNK], record=record, gap=gap))
            if progress is not None:
                progress(min(CHUNK, x.shape[0] - start))
        result = merge(parts)
    return BundleEmulation(network, result, int(x.shape[0]), int(x.shape[1]), padded, shift, note, implementation)


def small(network, samples: int, steps: int) -> bool:
    """Whether the numpy statement runs ``samples`` x ``steps`` of ``network`` (module docstring's bounds)."""
    layers = network.layers[1:]
    if steps * len(layers) > STATEMENT_LAYER_STEPS:
        return False
    per_step = sum(w.size * np.unique(np.asarray(d)).size for lay in layers
                   for w, d in ((lay.weight, lay.delay), (lay.weight_rec, lay.delay_rec)) if w is not None)
    return samples * steps * per_step <= STATEMENT_WORK


def merge(parts):
    """One EmulationResult from the results of consecutive chunks of samples."""
    from snncc.targets.loihi.emulation.emulator import EmulationResult

    if len(parts) == 1:
        return parts[0]
    first = parts[0]
    res = EmulationResult(
        output_spikes=np.concatenate([p.output_spikes for p in parts]),
        counts=np.concatenate([p.counts for p in parts]),
        prediction=np.concatenate([p.prediction for p in parts]),
        overflow={k: sum(p.overflow[k] for p in parts) for k in first.overflow},
    )
    for name in ("spikes", "voltage", "current"):
        for i in getattr(first, name):
            getattr(res, name)[i] = np.concatenate([getattr(p, name)[i] for p in parts])
    return res
