"""The integer network a C artefact runs: plain data that the code generator, the emulator and the fine-tuning
student all read (``CNetwork``), and its file (``network.npz`` in the artefact: integer arrays plus a JSON
header, byte-identical for identical networks).

    CPopulation   a LIF population: F (state fraction bits), per-neuron int32 threshold, Q16 alpha and beta,
                  reset, refractory steps, spike rule, voltage bias, current-bias terms (start step, int32 vector)
    CProjection   spikes of a source (the input, -1, or a population index) after ``delay`` steps into a target
                  population: int8/int16 weights ``(n_source, n_target)`` stored dense or as fan-out rows (CSR),
                  and per target neuron an exponent e (weight scale 2**e state units)

Everything here is an integer except the float reading (``float_weight`` etc.) used by checks.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from snncc.targets.kit import SnnccError

SYNAPTIC_BITS = 52      # one step's synaptic input stays below 2**52 units: exact in int64 and in float64


@dataclass
class BiasTerm:
    start: int                       # first step at which it is added to the current
    values: np.ndarray               # (n,) int32 state units


@dataclass
class CPopulation:
    name: str
    n: int
    frac_bits: int                   # F: one state unit is 2**-F of the model's units
    threshold: np.ndarray            # (n,) int64 (>= 1; INT32_MAX for a non-spiking integrator)
    alpha: np.ndarray                # (n,) int64, Q16
    beta: np.ndarray                 # (n,) int64, Q16
    reset: str                       # "zero" | "subtract"
    refractory: int                  # >= 1 (1: none)
    fire_test: str                   # ">" | ">="
    max_spikes: int
    bias_v: np.ndarray | None = None             # (n,) int64 added to V every step
    bias_i: list[BiasTerm] = field(default_factory=list)
    fires: bool = True               # False: a non-spiking integrator (threshold +inf)

    @property
    def counts(self) -> bool:
        """True when an event may carry more than one spike."""
        return self.max_spikes > 1


@dataclass
class CProjection:
    source: int                      # -1: the input; else a population index
    target: int
    delay: int
    bits: int                        # 8 or 16
    weights: np.ndarray              # (n_source, n_target) int16 (fan-out rows; int8 values for 8-bit rules)
    exponent: np.ndarray             # (n_target,) int64, 0..MAX_EXPONENT
    layout: str = "dense"            # "dense" | "sparse" (CSR fan-out rows)
    origin: str = ""                 # the IR nodes it came from (for people)

    @property
    def per_layer(self) -> bool:
        return bool(self.exponent.size == 0 or np.all(self.exponent == self.exponent[0]))

    def csr(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(row_ptr (n_source + 1), target indices, weights) of the nonzero weights, row by row."""
        rows, cols = np.nonzero(self.weights)
        ptr = np.zeros(self.weights.shape[0] + 1, np.int64)
        np.add.at(ptr, rows + 1, 1)
        return np.cumsum(ptr), cols.astype(np.int64), self.weights[rows, cols].astype(np.int64)

    def column_sums(self) -> np.ndarray:
        """Per target neuron, the sum of |w| over its sources (int64)."""
        return np.abs(self.weights.astype(np.int64)).sum(axis=0)


@dataclass
class CNetwork:
    """The integer network: populations in update order, projections, the input width, the output population."""

    dt: float
    inputs: int
    populations: list[CPopulation]
    projections: list[CProjection]
    output: int                      # index of the population whose spikes are the outputs
    rule: str = ""                   # the weight rule that made it
    steps: int = 100                 # a sample's steps (the artefact's time base)
    names: dict[str, Any] = field(default_factory=dict)   # input node name, readout name (for people)

    @property
    def outputs(self) -> int:
        return self.populations[self.output].n

    def into(self, p: int) -> list[CProjection]:
        return [q for q in self.projections if q.target == p]

    def source_size(self, source: int) -> int:
        return self.inputs if source < 0 else self.populations[source].n

    def max_delay(self, source: int) -> int:
        return max((q.delay for q in self.projections if q.source == source), default=0)

    def source_counts(self, source: int) -> int:
        """The largest spike count one event of ``source`` carries."""
        return 1 if source < 0 else self.populations[source].max_spikes


# -- the file --------------------------------------------------------------------------------------------------
def _header(net: CNetwork) -> dict[str, Any]:
    pops = [{"name": p.name, "n": p.n, "frac_bits": p.frac_bits, "reset": p.reset, "refractory": p.refractory,
             "fire_test": p.fire_test, "max_spikes": p.max_spikes, "fires": p.fires,
             "bias_v": p.bias_v is not None, "bias_i_starts": [t.start for t in p.bias_i]} for p in net.populations]
    projs = [{"source": q.source, "target": q.target, "delay": q.delay, "bits": q.bits, "layout": q.layout,
              "origin": q.origin} for q in net.projections]
    return {"dt": net.dt, "inputs": net.inputs, "output": net.output, "rule": net.rule, "steps": net.steps,
            "names": net.names, "populations": pops, "projections": projs}


def network_arrays(net: CNetwork) -> dict[str, np.ndarray]:
    """The arrays of ``network.npz`` (int64 except the header, JSON text as uint8)."""
    out: dict[str, np.ndarray] = {"header": np.frombuffer(json.dumps(_header(net), sort_keys=True).encode(), np.uint8)}
    for i, p in enumerate(net.populations):
        for key in ("threshold", "alpha", "beta"):
            out[f"p{i}_{key}"] = np.asarray(getattr(p, key), np.int64)
        if p.bias_v is not None:
            out[f"p{i}_bias_v"] = np.asarray(p.bias_v, np.int64)
        for k, term in enumerate(p.bias_i):
            out[f"p{i}_bias_i{k}"] = np.asarray(term.values, np.int64)
    for k, q in enumerate(net.projections):
        out[f"w{k}"] = np.asarray(q.weights, np.int16)
        out[f"e{k}"] = np.asarray(q.exponent, np.int64)
    return out


def network_bytes(net: CNetwork) -> bytes:
    from snncc.targets.kit.writing import npz_bytes

    return npz_bytes(network_arrays(net))


def read_network(data: bytes, *, source: str | None = None) -> CNetwork:
    """A ``CNetwork`` from ``network.npz`` bytes; a malformed file is refused in one line."""
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        head = json.loads(bytes(arrays["header"].astype(np.uint8)).decode("utf-8"))
        pops = []
        for i, h in enumerate(head["populations"]):
            pops.append(CPopulation(
                name=str(h["name"]), n=int(h["n"]), frac_bits=int(h["frac_bits"]),
                threshold=arrays[f"p{i}_threshold"].astype(np.int64), alpha=arrays[f"p{i}_alpha"].astype(np.int64),
                beta=arrays[f"p{i}_beta"].astype(np.int64), reset=str(h["reset"]), refractory=int(h["refractory"]),
                fire_test=str(h["fire_test"]), max_spikes=int(h["max_spikes"]), fires=bool(h["fires"]),
                bias_v=arrays[f"p{i}_bias_v"].astype(np.int64) if h["bias_v"] else None,
                bias_i=[BiasTerm(int(s), arrays[f"p{i}_bias_i{k}"].astype(np.int64))
                        for k, s in enumerate(h["bias_i_starts"])]))
        projs = [CProjection(source=int(h["source"]), target=int(h["target"]), delay=int(h["delay"]),
                             bits=int(h["bits"]), weights=arrays[f"w{k}"].astype(np.int16),
                             exponent=arrays[f"e{k}"].astype(np.int64), layout=str(h["layout"]),
                             origin=str(h.get("origin", "")))
                 for k, h in enumerate(head["projections"])]
        net = CNetwork(dt=float(head["dt"]), inputs=int(head["inputs"]), populations=pops, projections=projs,
                       output=int(head["output"]), rule=str(head["rule"]), steps=int(head["steps"]),
                       names=dict(head.get("names") or {}))
    except (KeyError, ValueError, TypeError, OSError) as ex:
        raise SnnccError(f"is not a readable C network ({type(ex).__name__}: {ex})", file=source,
                         field="network.npz") from None
    check_network(net, source)
    return net


def check_network(net: CNetwork, source: str | None = None) -> None:
    """The ranges the C code relies on (what the code generator and the emulator assume), else one line."""
    from snncc.targets.c.options import MAX_DELAY, MAX_EXPONENT, MAX_SPIKES, WEIGHT_LIMIT

    def refuse(rule: str, where: str) -> None:
        raise SnnccError(rule, file=source, field=where)

    int32 = (-(1 << 31), (1 << 31) - 1)
    if not net.populations or not 0 <= net.output < len(net.populations) or net.inputs < 1:
        refuse("needs an input, at least one population and an output population", "network.npz")
    for i, p in enumerate(net.populations):
        where = f"population {i} ({p.name})"
        if p.n < 1 or any(np.shape(getattr(p, k)) != (p.n,) for k in ("threshold", "alpha", "beta")):
            refuse("sizes do not match", where)
        if np.any(p.threshold < 1) or np.any(p.threshold > int32[1]):
            refuse("thresholds must be 1 .. 2**31 - 1", where)
        for key in ("alpha", "beta"):
            if np.any(np.abs(getattr(p, key)) > (1 << 16)):
                refuse(f"{key} must be a Q16 multiplier in [-1, 1]", where)
        if p.reset not in ("zero", "subtract") or p.fire_test not in (">", ">=") \
                or not 1 <= p.max_spikes <= MAX_SPIKES or not 1 <= p.refractory <= 65535:
            refuse("reset, spike rule or refractory period out of range", where)
        for vec in ([p.bias_v] if p.bias_v is not None else []) + [t.values for t in p.bias_i]:
            if np.shape(vec) != (p.n,) or np.any(vec < int32[0]) or np.any(vec > int32[1]):
                refuse("biases must be int32 vectors of the population's size", where)
    for k, q in enumerate(net.projections):
        where = f"projection {k}"
        if not -1 <= q.source < len(net.populations) or not 0 <= q.target < len(net.populations):
            refuse("names a population that does not exist", where)
        if q.weights.shape != (net.source_size(q.source), net.populations[q.target].n) or \
                q.exponent.shape != (net.populations[q.target].n,):
            refuse("weight or exponent shape does not match its populations", where)
        if q.bits not in WEIGHT_LIMIT or q.weights.dtype != np.int16 or \
                np.any(np.abs(q.weights.astype(np.int64)) > WEIGHT_LIMIT[q.bits]):
            refuse("weights exceed their declared width", where)
        if np.any(q.exponent < 0) or np.any(q.exponent > MAX_EXPONENT) or not 0 <= q.delay <= MAX_DELAY:
            refuse("exponent or delay out of range", where)
        if q.layout not in ("dense", "sparse"):
            refuse("layout must be dense or sparse", where)
        if q.delay == 0 and q.source >= q.target:
            refuse("a zero-delay projection must come from a population updated earlier", where)
        fan_in = q.column_sums().max(initial=0) * net.source_counts(q.source)
        if fan_in >= (1 << 31):
            refuse("its accumulator could overflow int32", where)
    for i, p in enumerate(net.populations):
        bound = np.zeros(p.n)
        for q in net.into(i):
            bound += q.column_sums() * net.source_counts(q.source) * np.exp2(q.exponent)
        if np.any(bound >= 2.0 ** SYNAPTIC_BITS):
            refuse(f"its synaptic input could reach 2**{SYNAPTIC_BITS} state units", f"population {i} ({p.name})")


__all__ = ["BiasTerm", "CPopulation", "CProjection", "CNetwork", "network_arrays", "network_bytes", "read_network",
           "check_network"]
