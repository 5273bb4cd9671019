"""NeuroBench's metrics (``neurobench`` 2.3.0, ``neurobench/metrics/``), computed from a network's projections and
the spikes of a run: for the float graph (the IR reference's run) and for a deployed artefact (its emulator's run,
its synapses as stored).

    footprint              bytes of the parameters and buffers: the float graph's as float32 (every weight and bias,
                           each neuron's alpha, beta and threshold); an artefact's as deployed (its target says what
                           it counts)
    connection_sparsity    zero weights / all weights over the synaptic projections (Linear and Conv layers; spiking
                           layers and pooling count nothing)
    activation_sparsity    zero activations / all activations of every spiking population, over every time step and
                           sample (the input is not an activation)
    synaptic_operations    per sample: ``Dense`` = every weight at every step (in x out per projection and step),
                           ``Effective_ACs`` = non-zero inputs x non-zero weights where the projection's input is binary
                           (spikes), ``Effective_MACs`` the same where it is graded; biases excluded; binary or
                           graded is decided per sample and step (NeuroBench decides per layer call: the same at
                           batch size 1); a synaptic layer behind a pooling sees the pooled sums, as in a torch model

A projection's input at step t is its source's output at step t - delay (zeros before), as NeuroBench's hooks see
a layer called once per step. ``tests/measure/test_neurobench.py`` runs the ``neurobench`` package's own metrics on
the float graph built as an snnTorch module and compares.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from snncc.ir.graph import Graph

NAMES = ("footprint", "connection_sparsity", "activation_sparsity", "synaptic_operations")


@dataclass
class Projection:
    """A synaptic projection as deployed: ``weight`` (out, in) (dense array or scipy sparse matrix, the stored
    values: a weight rounded to 0 is zero), fed by ``source`` (a population's name or an input's) ``delay`` steps
    late."""

    source: str
    target: str
    weight: Any
    delay: int = 0
    pooling: Any = None     # (in, source width): the pooling between source and weight (its output is what the
                            # synaptic layer sees, graded: NeuroBench counts MACs there); None: fed directly


@dataclass
class NeuroBenchFigures:
    """NeuroBench 2.3's names and values (module doc), with what was counted."""

    footprint: int
    connection_sparsity: float
    activation_sparsity: float
    synaptic_operations: dict[str, float]
    counted: str = ""
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def _nonzero_matrix(weight: Any) -> Any:
    """The 0/1 pattern of ``weight`` (dense float64, or scipy CSR), for counting operations."""
    if isinstance(weight, np.ndarray):
        return (weight != 0).astype(np.float64)
    pattern = weight.tocsr(copy=True)
    pattern.eliminate_zeros()
    pattern.data = np.ones_like(pattern.data, dtype=np.float64)
    return pattern


def _sizes(weight: Any) -> tuple[int, int]:
    out, inp = weight.shape
    return int(out), int(inp)


def _shifted(x: np.ndarray, delay: int) -> np.ndarray:
    if delay <= 0:
        return x
    out = np.zeros_like(x)
    if delay < x.shape[1]:
        out[:, delay:] = x[:, :-delay]
    return out


class Tally:
    """NeuroBench's workload metrics gathered chunk by chunk (memory bounded by the chunk): ``add(activity)`` with
    every source's and population's (B, T, n) outputs of the same samples, then ``synaptic_operations()`` and
    ``activation_sparsity()``."""

    def __init__(self, projections: Sequence[Projection], populations: Sequence[str]) -> None:
        self.projections = list(projections)
        self.populations = list(populations)
        self.patterns = [np.asarray(_nonzero_matrix(p.weight).sum(axis=0)).reshape(-1) for p in self.projections]
        self.samples = 0
        self.mac = self.ac = self.dense = 0.0
        self.activations = self.nonzero = 0

    def add(self, activity: Mapping[str, np.ndarray]) -> None:
        b = None
        for p, fan_out in zip(self.projections, self.patterns):
            x = np.asarray(activity[p.source])
            b, t, _ = x.shape
            out, inp = _sizes(p.weight)
            self.dense += float(out) * float(inp) * t * b
            fed = _shifted(x, int(p.delay)).reshape(b * t, -1)
            if p.pooling is not None:                    # the synaptic layer sees the pooled activity
                fed = np.asarray(p.pooling @ fed.T).T
            ops = (fed != 0) @ fan_out                   # per (sample, step): non-zero inputs x their non-zero weights
            binary = np.all((fed == 0) | (fed == 1) | (fed == -1), axis=1)
            self.ac += float(ops[binary].sum())
            self.mac += float(ops[~binary].sum())
        for name in self.populations:
            a = np.asarray(activity[name])
            b = int(a.shape[0])
            self.activations += int(a.size)
            self.nonzero += int(np.count_nonzero(a))
        self.samples += int(b or 0)

    def synaptic_operations(self) -> dict[str, float]:
        n = self.samples or 1
        return {"Effective_MACs": self.mac / n, "Effective_ACs": self.ac / n, "Dense": self.dense / n}

    def activation_sparsity(self) -> float:
        return (self.activations - self.nonzero) / self.activations if self.activations else 0.0


def synaptic_operations(projections: Sequence[Projection], activity: Mapping[str, np.ndarray]) -> dict[str, float]:
    """``Effective_MACs``, ``Effective_ACs`` and ``Dense`` per sample (module doc); ``activity``: every source's
    output (B, T, n) by name."""
    tally = Tally(projections, [])
    tally.add(activity)
    return tally.synaptic_operations()


def activation_sparsity(populations: Mapping[str, np.ndarray]) -> float:
    """Zero activations / all activations over every population's (B, T, n) outputs (0.0 without any)."""
    tally = Tally([], list(populations))
    tally.add(populations)
    return tally.activation_sparsity()


def connection_sparsity(projections: Sequence[Projection]) -> float:
    """Zero weights / all weights over ``projections`` (NeuroBench rounds it to 3 decimals; this does not)."""
    total = zeros = 0
    for p in projections:
        out, inp = _sizes(p.weight)
        size = out * inp
        nonzero = int(np.count_nonzero(p.weight)) if isinstance(p.weight, np.ndarray) else int(p.weight.count_nonzero())
        total += size
        zeros += size - nonzero
    return zeros / total if total else 0.0


def from_tally(tally: Tally, footprint: int, counted: str, notes: Sequence[str] = ()) -> NeuroBenchFigures:
    """The four figures from a filled ``Tally`` and the caller's footprint."""
    return NeuroBenchFigures(int(footprint), connection_sparsity(tally.projections), tally.activation_sparsity(),
                             tally.synaptic_operations(), counted, list(notes))


def figures(projections: Sequence[Projection], populations: Mapping[str, np.ndarray],
            inputs: Mapping[str, np.ndarray], footprint: int, counted: str) -> NeuroBenchFigures:
    """NeuroBench's four metrics from ``projections`` (as deployed), every spiking population's (B, T, n) run and the
    inputs by name (what the projections fed from an input read); ``footprint`` and what it counted from the caller."""
    tally = Tally(projections, list(populations))
    tally.add({**{k: np.asarray(v) for k, v in inputs.items()}, **{k: np.asarray(v) for k, v in populations.items()}})
    return from_tally(tally, footprint, counted)


# -- the float graph -----------------------------------------------------------------------------------------
def is_pooling(op: Any) -> bool:
    """A Conv node that only pools (one constant kernel per channel, grouped by channel): no trained weights, and
    not a synaptic layer for NeuroBench."""
    from snncc.ir.nodes import Conv

    return (isinstance(op, Conv) and op.weight.shape[1] == 1 and op.groups == op.in_shape[0]
            and bool(np.all(op.weight == op.weight.flat[0])))


def graph_projections(graph: Graph) -> tuple[list[Projection], list[str]]:
    """(the float graph's synaptic projections, the notes on what was folded): each Dense or Conv node whose
    source is a population or an input; a chain of linear nodes between two populations (a pooling Conv and a
    Dense, say) is one projection per synaptic node, the pooling fed through (NeuroBench counts no pooling)."""
    from snncc.ir.conv import conv_matrix
    from snncc.ir.nodes import LIF, Conv, Dense, Input

    out: list[Projection] = []
    notes: list[str] = []
    for name, op in graph.items():
        if not isinstance(op, (Dense, Conv)) or is_pooling(op):
            continue
        preds = list(graph.predecessors(name))
        if len(preds) != 1:
            continue
        src, delay = preds[0], graph.delay(preds[0], name)
        pooling = None
        while isinstance(graph.node(src), (Dense, Conv)) and is_pooling(graph.node(src)):
            up = list(graph.predecessors(src))[0]
            delay += graph.delay(up, src)
            pool = conv_matrix(graph.node(src))
            pooling = pool if pooling is None else pooling @ pool
            notes.append(f"{src}: pooling, not a synaptic layer (NeuroBench counts none); its sums feed {name}")
            src = up
        if not isinstance(graph.node(src), (LIF, Input)):
            notes.append(f"{name}: fed by {src}, neither a population nor an input: not counted")
            continue
        weight = conv_matrix(op) if isinstance(op, Conv) else np.asarray(op.weight)
        out.append(Projection(src, name, weight, int(delay), pooling))
    return out, notes


def float_footprint(graph: Graph) -> int:
    """Bytes of the float graph as a float32 torch model: every Dense/Conv weight and bias (pooling included: a
    torch model stores its kernel only if it is a Conv layer; here none is counted for a pooling node), and each
    LIF neuron's alpha, beta and threshold."""
    from snncc.ir.nodes import LIF, Conv, Dense

    count = 0
    for _, op in graph.items():
        if isinstance(op, (Dense, Conv)) and not is_pooling(op):
            count += int(np.size(op.weight)) + (0 if op.bias is None else int(np.size(op.bias)))
        elif isinstance(op, LIF):
            count += 3 * int(op.n)
    return 4 * count


FLOAT_COUNTED = ("float32 weights, biases and each neuron's alpha, beta and threshold (the float graph as a torch "
                 "model)")


def float_figures(graph: Graph, inputs: np.ndarray, progress=None) -> NeuroBenchFigures:
    """NeuroBench's metrics of the float graph on ``inputs`` (B, T, C): the IR reference run chunk by chunk."""
    from snncc.ir.nodes import LIF, Input
    from snncc.ir.simulate import simulate
    from snncc.measure.agreement import chunk_size
    from snncc.threads import one_thread

    projections, notes = graph_projections(graph)
    lifs = [n for n, op in graph.items() if isinstance(op, LIF)]
    name = graph.of_kind(Input)[0]
    tally = Tally(projections, lifs)
    x = np.asarray(inputs)
    step = chunk_size(max(1, sum(int(graph.node(p).n) for p in lifs)), int(x.shape[1]), 64)
    with one_thread():
        for start in range(0, x.shape[0], step):
            part = x[start:start + step]
            run = simulate(graph, part, record="spikes")
            tally.add({name: part, **{n: run.spikes[n] for n in lifs}})
            if progress is not None:
                progress(int(part.shape[0]))
    return from_tally(tally, float_footprint(graph), FLOAT_COUNTED, notes)
