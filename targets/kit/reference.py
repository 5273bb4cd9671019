"""The float graph on given inputs, run by the IR reference simulator (``snncc.ir.simulate``), in chunks.

Every measurement compares an artefact with this: the float graph's output spike counts (or any
population's), computed chunk by chunk so memory stays bounded whatever the sample count
(``snncc.measure.agreement.chunk_size``: at most 2^24 neuron-steps at once), on one compute thread.

    readout_population(graph)            the spiking population whose counts are the decision (the last LIF)
    float_counts(graph, x)               (B, n) output spike counts
    float_spikes(graph, x, populations)  per population (B, T, n) uint8 spikes, for small runs
    perturbed(graph, noise, seed)        every trained weight (and bias) times 1 + noise * N(0, 1)
    float_scores(graph, x)               (B, classes): spike counts, or an LSTM's readout scores
    noise_ceiling(graph, x, counts)      the float graph's agreement with itself under that perturbation:
                                         how much of an artefact's disagreement any 1 % weight error causes
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from snncc.measure.agreement import ArgmaxAgreement, argmax_agreement, chunk_size

if TYPE_CHECKING:
    from snncc.ir.graph import Graph

DEFAULT_NOISE = 0.01
NOISE_SEED = 9
CHUNK = 64


def spiking_neurons(graph: Graph) -> int:
    """Neurons of every LIF population (what one step of a sample costs the reference)."""
    from snncc.ir.nodes import LIF

    return int(sum(int(graph.node(p).n) for p in graph.of_kind(LIF)))


def readout_population(graph: Graph) -> str:
    """The LIF population whose spike counts are the model's decision: the last one in the graph's order."""
    from snncc.errors import SnnccError
    from snncc.ir.nodes import LIF

    names = [n for n, op in graph.items() if isinstance(op, LIF)]
    if not names:
        raise SnnccError("the model has no spiking population whose counts could be compared", field="model")
    return names[-1]


def _chunks(graph: Graph, x: np.ndarray, most: int) -> int:
    return chunk_size(max(1, spiking_neurons(graph)), int(x.shape[1]), most)


def float_counts(graph: Graph, x: np.ndarray, population: str | None = None, *, most: int = CHUNK,
                 progress: Callable[[int], None] | None = None) -> np.ndarray:
    """(B, n) int64 spike counts of ``population`` (default: the readout) of the float graph on ``x`` (B, T, C)."""
    from snncc.ir.simulate import simulate
    from snncc.threads import one_thread

    name = population or readout_population(graph)
    x = np.asarray(x)
    step = _chunks(graph, x, most)
    out = []
    with one_thread():
        for start in range(0, x.shape[0], step):
            part = x[start:start + step]
            spikes = np.asarray(simulate(graph, part, record="spikes", populations=[name]).spikes[name])
            out.append(spikes.sum(axis=1).astype(np.int64))
            if progress is not None:
                progress(int(part.shape[0]))
    if not out:
        return np.zeros((0, int(graph.node(name).n)), np.int64)
    return np.concatenate(out)


def is_spiking(graph: Graph) -> bool:
    """The graph decides by counting a spiking population's spikes (else by a readout's scores: an LSTM)."""
    from snncc.ir.nodes import LIF

    return any(isinstance(op, LIF) for _, op in graph.items())


def float_scores(graph: Graph, x: np.ndarray, *, most: int = CHUNK) -> np.ndarray:
    """(B, classes) what the float graph decides by: the readout's spike counts for a spiking graph, else its
    readout's scores (an LSTM's last output), chunk by chunk."""
    from snncc.ir.simulate import simulate
    from snncc.threads import one_thread

    if is_spiking(graph):
        return float_counts(graph, x, most=most)
    x = np.asarray(x)
    out = []
    with one_thread():
        for start in range(0, x.shape[0], most):
            res = simulate(graph, x[start:start + most])
            out.append(np.asarray(res.readout if res.readout is not None else res.output[:, -1]))
    return np.concatenate(out)


def float_spikes(graph: Graph, x: np.ndarray, populations: Sequence[str] | None = None) -> dict[str, np.ndarray]:
    """Per population (default: every LIF), (B, T, n) uint8 spikes of the float graph on ``x`` (one run: for a
    handful of samples)."""
    from snncc.ir.nodes import LIF
    from snncc.ir.simulate import simulate
    from snncc.threads import one_thread

    names = list(populations) if populations is not None else [n for n, op in graph.items() if isinstance(op, LIF)]
    with one_thread():
        run = simulate(graph, np.asarray(x), record="spikes", populations=names)
    return {n: np.asarray(run.spikes[n]).astype(np.uint8) for n in names}


def perturbed(graph: Graph, noise: float, seed: int = NOISE_SEED) -> Graph:
    """A copy of ``graph`` with every Dense and Conv weight (and bias) multiplied by 1 + noise * N(0, 1), seeded
    (pooling kernels, which hold no trained weights, are left as they are)."""
    from snncc.ir.nodes import Conv, Dense

    g = graph.copy()
    rng = np.random.default_rng(seed)
    for _, op in g.items():
        pooling = (isinstance(op, Conv) and op.weight.shape[1] == 1 and op.groups == op.in_shape[0]
                   and bool(np.all(op.weight == op.weight.flat[0])))
        if isinstance(op, (Dense, Conv)) and not pooling:
            op.weight = op.weight * (1.0 + noise * rng.standard_normal(op.weight.shape))
            if op.bias is not None:
                op.bias = op.bias * (1.0 + noise * rng.standard_normal(np.shape(op.bias)))
    return g


def noise_ceiling(graph: Graph, x: np.ndarray, counts: np.ndarray, noise: float = DEFAULT_NOISE,
                  seed: int = NOISE_SEED) -> ArgmaxAgreement:
    """Agreement of ``perturbed(graph, noise, seed)`` with the float graph's own ``counts`` (its ``float_scores``)
    on ``x``."""
    spiking = is_spiking(graph)
    return argmax_agreement(counts, float_scores(perturbed(graph, noise, seed), x), spiking=spiking)


__all__ = ["DEFAULT_NOISE", "NOISE_SEED", "float_counts", "float_scores", "float_spikes", "is_spiking", "noise_ceiling",
           "perturbed", "readout_population", "spiking_neurons"]
