"""Checks a lowered Loihi network against the IR reference, on seeded random input spikes.

Exact checks (a mismatch is an ``InternalError``, a bug in snncc, never a warning):
  1. timing: the lowered network run with the IR's float parameters in the registers' place
     (``reference_run(arithmetic="float")``) equals the IR reference of the graph in the order Loihi
     runs, spike for spike in every layer (population shifts applied);
  2. quantized parameters: the same float pipeline with the quantized weights, thresholds and
     decays equals the IR reference of the quantized graph, spike for spike;
  3. integer arithmetic: the fast kernel equals the readable integer statement, spikes, u and v.
Measured (reported, not errors): the emulator against the quantized IR (truncating decays and
overflow are the only differences left) and against the float model as trained.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from snncc.targets.kit import InternalError
from snncc.targets.kit.compute import one_thread
from snncc.ir.graph import Graph
from snncc.targets.loihi.emulation.emulator import EmulationResult, emulate, lead_steps, pad, reference_run  # noqa: F401
from snncc.targets.loihi.lowering.registers import ChainLayer, float_twin
from snncc.targets.loihi.network import LoihiNetwork


VALIDATION_RATE, VALIDATION_SEED = 0.05, 0


def random_spikes(batch: int, steps: int, width: int, rate: float, seed: int) -> np.ndarray:
    return (np.random.default_rng(seed).random((batch, steps, width)) < rate).astype(np.uint8)


def validation_spikes(batch: int, steps: int, width: int) -> np.ndarray:
    """The validation's inputs: ``batch`` seeded random spike trains (p = VALIDATION_RATE, seed VALIDATION_SEED)."""
    return random_spikes(batch, steps, width, VALIDATION_RATE, VALIDATION_SEED)


def ir_spikes(graph: Graph, x: np.ndarray, names: list[str]) -> dict[str, np.ndarray]:
    from snncc.ir.simulate import simulate   # torch: imported where the reference runs, not by lowering

    with one_thread():
        res = simulate(graph, x, record="spikes")
    return {n: np.asarray(res.spikes[n]).astype(np.uint8) for n in names}


def loihi_spikes(result: EmulationResult, network: LoihiNetwork, layers: list[ChainLayer], shifts: dict[str, int],
                 steps: int) -> dict[str, np.ndarray]:
    """Emulated spikes per population, undoing each population's timing shift, cut to ``steps``
    (the always-on bias compartments left out)."""
    out = {}
    for i, c in enumerate(layers, start=1):
        s = shifts.get(c.lif, 0)
        out[c.lif] = result.spikes[i][:, s:s + steps, :network.layers[i].model_n]
    return out


def agreement(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> dict[str, float | None]:
    """Share of equal spike entries per layer; None where both are silent (nothing to agree on)."""
    return {k: None if not a[k].any() and not b[k].any() else float(np.mean(a[k] == b[k])) for k in a}


@dataclass
class ValidationRecord:
    inputs: str
    timing_exact: bool = False              # check 1
    quantized_params_exact: bool = False    # check 2
    kernel_exact: bool = False              # check 3
    trained_vs_loihi_order: dict[str, float] = field(default_factory=dict)   # IR as trained vs IR in Loihi order
    emulator_vs_quantized_ir: dict[str, float] = field(default_factory=dict)
    emulator_vs_trained: dict[str, float] = field(default_factory=dict)
    prediction_agreement: float | None = None   # emulator vs float model as trained (None: undefined, outputs silent)
    prediction: dict[str, Any] = field(default_factory=dict)   # kit.agreement.ArgmaxAgreement
    overflow: dict[str, int] = field(default_factory=dict)
    spike_counts: dict[str, dict[str, int]] = field(default_factory=dict)   # "emulator" / "float": population -> spikes

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def _same(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> str | None:
    for k in a:
        if not np.array_equal(a[k], b[k]):
            t = int(np.argwhere(a[k] != b[k])[0][1])
            return f"layer '{k}' first differs at step {t}"
    return None


def twin_spikes(network: LoihiNetwork, graph: Graph, layers: list[ChainLayer], xp: np.ndarray, shifts: dict[str, int],
                steps: int) -> dict[str, np.ndarray]:
    """Per population, the spikes of ``network`` run with ``graph``'s float parameters in its registers' place
    (``float_twin``, exact float, no truncation) on the padded inputs ``xp``: the IR's spikes whenever the
    lowering's timing is right (``validate_lowering`` checks that, spike for spike, on every compile)."""
    with one_thread():
        twin_net = float_twin(network, graph, layers)
        twin = reference_run(twin_net, xp, arithmetic="float", record="spikes")
    return loihi_spikes(twin, twin_net, layers, shifts, steps)


def twin_structure(network: LoihiNetwork, graph: Graph, layers: list[ChainLayer]) -> str:
    """SHA-256 of what ``float_twin`` takes from ``network`` (sizes, delays, refractory periods, the always-on bias
    sources' registers): networks with equal digests have the same float twin of ``graph``, so one twin run serves
    them all (the scale candidates', the written bundle's)."""
    import hashlib

    h = hashlib.sha256()
    for c, lay in zip(layers, network.layers[1:]):
        n = graph.node(c.lif).n
        h.update(repr((lay.name, lay.kind, lay.n, np.shape(lay.weight), lay.ref_delay, lay.always_on,
                       np.shape(lay.weight_rec), lay.bias_exp if lay.always_on else None)).encode())
        for a in (lay.delay, lay.delay_rec):
            h.update(np.ascontiguousarray(np.asarray(a, np.int64)).tobytes() if a is not None else b"-")
        for a in (lay.i_decay, lay.v_decay, lay.v_th_mant, lay.bias):
            h.update(b"-" if a is None else np.ascontiguousarray(
                np.broadcast_to(np.asarray(a, np.float64), (lay.n,))[n:]).tobytes())
    return h.hexdigest()


def _check_twin(network: LoihiNetwork, graph: Graph, layers: list[ChainLayer], xp: np.ndarray, shifts: dict[str, int],
                steps: int, expected: dict[str, np.ndarray], field: str, what: str,
                twin: dict[str, np.ndarray] | None = None) -> None:
    """Run ``network`` with ``graph``'s float parameters (``float_twin``; ``twin``: that run's spikes, where they
    were already computed); any spike unlike ``expected`` is an error."""
    problem = _same(twin if twin is not None else twin_spikes(network, graph, layers, xp, shifts, steps), expected)
    if problem:
        raise InternalError(f"check failed: {what} ({problem})", field=field)


def validate_lowering(trained: Graph, order: Graph, quantized: Graph, network: LoihiNetwork, layers: list[ChainLayer],
                      shifts: dict[str, int], output_shift: int, *, batch: int = 4, steps: int | None = None,
                      rate: float = VALIDATION_RATE, seed: int = VALIDATION_SEED, prepared=None,
                      order_twin: tuple[np.ndarray, dict[str, np.ndarray]] | None = None) -> ValidationRecord:
    """The three exact checks (module docstring) on ``batch`` seeded random inputs; ``prepared``: ``network``
    already flattened for the kernel (``emulator.PreparedNetwork``), else it is flattened here; ``order_twin``:
    (inputs, ``twin_spikes(network, order, ...)`` on them) where lowering already ran it (the same run: the float
    twin takes its structure from ``network``'s timing, which every scale rule shares), used when those inputs
    are this check's."""
    steps = int(steps or network.t_sample - output_shift)
    x = random_spikes(batch, steps, network.input_width, rate, seed)
    known_twin = order_twin[1] if order_twin is not None and np.array_equal(order_twin[0], x) else None
    xp = pad(x, lead_steps(shifts, output_shift))
    names = [c.lif for c in layers]
    record = ValidationRecord(inputs=f"{batch} seeded random spike trains (p={rate}, seed {seed}), {steps} steps")
    ir_trained = ir_spikes(trained, x, names)
    ir_order = ir_trained if order is trained else ir_spikes(order, x, names)
    ir_quant = ir_spikes(quantized, x, names)
    record.trained_vs_loihi_order = agreement(ir_order, ir_trained)

    _check_twin(network, order, layers, xp, shifts, steps, ir_order, "timing",
                "the lowered timing does not reproduce the IR in float", twin=known_twin)
    record.timing_exact = True
    _check_twin(network, quantized, layers, xp, shifts, steps, ir_quant, "quantization",
                "quantized registers do not reproduce the quantized IR")
    record.quantized_params_exact = True

    fast = emulate(network, xp, record="all") if prepared is None else prepared.run(xp, record="all")
    with one_thread():
        slow = reference_run(network, xp, record="all")
    for i in fast.spikes:
        same = np.array_equal(fast.spikes[i], slow.spikes[i])
        if i:
            same = same and np.array_equal(fast.voltage[i], slow.voltage[i]) and np.array_equal(fast.current[i], slow.current[i])
        if not same or fast.overflow != slow.overflow:
            raise InternalError(f"check failed: the emulator kernel differs from the chip's rules in layer {i}",
                             field="emulator")
    record.kernel_exact = True
    emu = loihi_spikes(fast, network, layers, shifts, steps)
    record.emulator_vs_quantized_ir = agreement(emu, ir_quant)
    record.emulator_vs_trained = agreement(emu, ir_trained)
    last = names[-1]
    from snncc.targets.kit.agreement import argmax_agreement

    decisions = argmax_agreement(ir_trained[last].sum(axis=1), emu[last].sum(axis=1))
    record.prediction_agreement = decisions.share
    record.prediction = decisions.as_dict()
    record.overflow = dict(fast.overflow)
    record.spike_counts = {"emulator": {k: int(v.sum()) for k, v in emu.items()},
                           "float": {k: int(v.sum()) for k, v in ir_trained.items()}}
    return record
