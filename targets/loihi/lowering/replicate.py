"""Precision by replication: K copies of every neuron that feeds another, so each weight is a sum of K.

Loihi 1 stores a weight as an even 8-bit mantissa with one exponent per projection (per-layer), so a
neuron's weights are resolved to about 1/127 of its largest one (at per-neuron scales). Replication
makes that resolution K times finer without leaving the format, and without changing what the
network computes:

    relay      R = K copies of every input channel j (R_{c,j}[t] = x_j[t]: a memoryless LIF, alpha = beta
               = 0, threshold 1/2, reset to zero), plus K always-on neurons (a voltage bias of 1) that carry
               the first population's current biases from step 0
    copies     every population but the last holds K copies of each neuron, P_{c,i} = P_i
    weights    W'[(c,i), (c',j)] = W[i, j] / K  for every copy c of the target and c' of the source
               (recurrent weights too; the biases' columns b_i / K from each always-on relay)

In float, sum_{c'} W[i,j] / K * s_{c',j}[t] = W[i,j] s_j[t]: every copy's membrane equals the original
neuron's, so the replicated graph's spikes are the original's (tested on every graph the Loihi tests
lower). On the chip each copy of W[i,j] rounds separately, so the sum reaches (K*127) levels of the row's
largest weight once the per-neuron scales grow by K (fine-tuning's starting points,
``targets/loihi/finetune/rescale.py``, do that; the lowering's own per-layer scale grows with max|W| / K).
Costs: K * inputs relay neurons and K - 1 more copies of every hidden neuron, K^2 times the synapses
between replicated populations, and one step of latency (the relay; the timing pass shifts the output
and tSample grows by one, so counts over a sample are unchanged).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense
from snncc.targets.kit.graphs import current_biases

from snncc.targets.loihi.options import MAX_REPLICAS

RELAY_THRESHOLD = 0.5      # a relay holds one input spike (1) for one step and fires on it; nothing else


def _free_name(graph: Graph, base: str) -> str:
    name, k = base, 1
    while name in graph:
        k += 1
        name = f"{base}{k}"
    return name


def replicate(graph: Graph, copies: int) -> tuple[Graph, dict[str, Any] | None]:
    """(the replicated graph, its record) for a chain ``Input -> Dense -> LIF (-> Dense -> LIF)*`` as the
    Loihi lowering reads it (``registers.chain``); ``copies`` 1 returns ``graph`` itself and None."""
    from snncc.targets.loihi.lowering.registers import chain

    k = int(copies)
    if k == 1:
        return graph, None
    if not 1 <= k <= MAX_REPLICAS:
        raise SnnccError(f"replicas must be a whole number from 1 to {MAX_REPLICAS}, got {copies}", field="--replicas")
    layers = chain(graph)
    if len(layers) < 2:
        raise SnnccError("replicas need a population that feeds another (a single population has no weights to "
                         "split)", field="--replicas")
    g = graph.copy()
    inp, first = layers[0].pre, layers[0]
    width = g.node(inp).width
    # the relays' always-on columns reach the population through its feed-forward Dense: from step 0 only if
    # that edge has no delay (otherwise the biases stay where they are, lowered as any current bias)
    start0 = [t for t in current_biases(g, first.lif) if t.start == 0] if g.delay(first.ff, first.lif) == 0 else []
    bias0 = start0[0].vector.copy() if start0 else None
    for origin in (start0[0].origins if start0 else ()):
        g.node(origin).bias = None          # carried by the always-on relays from step 0
    sources = k if bias0 is not None else 0
    n_relay = width * k + sources
    copy_in = np.zeros((n_relay, width))
    copy_in[:width * k] = np.tile(np.eye(width), (k, 1))
    relay_bias = np.zeros(n_relay)
    relay_bias[width * k:] = 1.0
    relay, relay_w = _free_name(g, "replica_relay"), _free_name(g, "replica_relay.w")
    g.add(relay_w, Dense(weight=copy_in))
    g.add(relay, LIF(n=n_relay, tau_syn=g.dt, tau_mem=g.dt, threshold=RELAY_THRESHOLD, reset="zero", refractory=1,
                     discretisation="euler", bias=relay_bias if sources else None, bias_placement="voltage"))
    delay_in = g.delay(inp, first.ff)
    g.nx.remove_edge(inp, first.ff)
    g.connect(inp, relay_w, delay_in)       # the input's delay before the relay: the biases still start at 0
    g.connect(relay_w, relay)
    g.connect(relay, first.ff)
    sizes = {}
    for i, c in enumerate(layers):
        kp = k if i < len(layers) - 1 else 1          # the readout population is not copied
        dense = g.node(c.ff)
        w = np.tile(dense.weight / k, (kp, k))
        if i == 0 and sources:
            w = np.concatenate([w, np.tile(np.tile(bias0, kp)[:, None] / k, (1, k))], axis=1)
        dense.weight = w
        if dense.bias is not None:
            dense.bias = np.tile(dense.bias, kp)
        if c.rec:
            rec = g.node(c.rec)
            rec.weight = np.tile(rec.weight / k, (k, k))
            if rec.bias is not None:
                rec.bias = np.tile(rec.bias, k)
        op = g.node(c.lif)
        sizes[c.lif] = [int(op.n), int(op.n) * kp]
        op.n = int(op.n) * kp
        for name in ("tau_syn", "tau_mem", "threshold"):
            setattr(op, name, np.tile(getattr(op, name), kp))
        if op.bias is not None:
            op.bias = np.tile(op.bias, kp)
    record = {"replicas": k, "relay": relay, "relay_dense": relay_w, "relay_neurons": width * k,
              "always_on_relays": sources, "populations": sizes,
              "rule": "each weight W[i,j] as K synapses of W[i,j]/K between copies (exact in float); the first "
                      "population's current biases from K always-on relays"}
    return g, record


def model_sizes(record: dict[str, Any] | None) -> dict[str, int]:
    """Population -> the model's own neuron count (copy 0 comes first) from a replication record."""
    if not record:
        return {}
    return {name: int(sizes[0]) for name, sizes in (record.get("populations") or {}).items()}



def replication_note(record: dict[str, Any]) -> str:
    """The compile report's line on a replicated network."""
    k = record["replicas"]
    copied = [f"{name} {sizes[0]} -> {sizes[1]}" for name, sizes in record["populations"].items() if sizes[1] != sizes[0]]
    sources = (f" + {record['always_on_relays']} always-on relays carrying the first population's current biases"
               if record["always_on_relays"] else "")
    return (f"replicas {k}: {record['relay']} relays each input channel {k} times ({record['relay_neurons']} neurons"
            f"{sources}); copies: {', '.join(copied)}; every weight is {k} synapses of W/{k} (exact in float; "
            f"{k}x finer weight steps once per-neuron scales use them, as fine-tuning's start does); one step of latency")
