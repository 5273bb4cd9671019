"""IR graph -> LoihiNetwork: structure checks, timing lowering, quantization, register values.

A graph Loihi 1 can run here is a chain of populations:

    Input(spikes) -> Dense -> LIF [<- Dense <- same LIF] -> Dense -> LIF ... -> Readout(spike_count) -> Output

Each LIF becomes one HDF5 layer (``dense`` or ``dense_rec``); layer 0 is the input axons.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from snncc.targets.kit import InternalError, SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LSTM, Dense, Input, Output, Readout
from snncc.targets.kit.graphs import current_biases
from snncc.targets.loihi import chip
from snncc.targets.loihi.lowering import bias_sources
from snncc.targets.loihi.lowering.quantize import QuantizationRecord, quantize_weights
from snncc.targets.loihi.lowering.timing import TimingRecord
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork


@dataclass
class ChainLayer:
    lif: str
    ff: str            # the Dense feeding it from the previous population
    pre: str           # the previous population (Input or LIF)
    rec: str | None    # the Dense of its recurrent loop


def chain(graph: Graph) -> list[ChainLayer]:
    """The populations of ``graph`` in order, or a one-line error saying what Loihi cannot express."""
    if graph.of_kind(LSTM):
        raise SnnccError("an LSTM cannot run on Loihi (a spiking neuromorphic chip); compile it for --target jetson",
                         field=f"node '{graph.of_kind(LSTM)[0]}'")
    inputs = graph.of_kind(Input)
    if len(inputs) != 1:
        raise SnnccError(f"the Loihi lowering needs exactly one Input, the graph has {len(inputs)}", field="graph")
    if graph.node(inputs[0]).signal != "spikes":
        raise SnnccError("Loihi input axons carry spikes; an analog input needs a spike encoder first",
                         field=f"node '{inputs[0]}'.signal")
    layers: list[ChainLayer] = []
    pre = inputs[0]
    seen = {pre}
    while True:
        ff = [s for s in graph.successors(pre) if isinstance(graph.node(s), Dense)
              and not (isinstance(graph.node(pre), LIF) and pre in graph.successors(s))]
        others = [s for s in graph.successors(pre) if not isinstance(graph.node(s), Dense)]
        if not ff:
            break
        if len(ff) > 1:
            raise SnnccError("the Loihi lowering handles chains: a population may feed one next population",
                             field=f"node '{pre}'")
        (dense,) = ff
        posts = graph.successors(dense)
        if len(posts) != 1 or not isinstance(graph.node(posts[0]), LIF):
            raise SnnccError("on Loihi a Dense must feed exactly one LIF population", field=f"node '{dense}'")
        lif = posts[0]
        if lif in seen:
            raise SnnccError("only self-recurrence (a LIF -> Dense -> same LIF loop) is supported on Loihi here",
                             field=f"node '{lif}'")
        if others and isinstance(graph.node(pre), LIF):
            raise SnnccError("a hidden population cannot also feed a readout on Loihi here", field=f"node '{pre}'")
        rec = [d for d in graph.successors(lif) if isinstance(graph.node(d), Dense) and lif in graph.successors(d)]
        if len(rec) > 1:
            raise SnnccError("at most one recurrent projection per population", field=f"node '{lif}'")
        expected = {dense} | set(rec)
        if set(graph.predecessors(lif)) != expected:
            raise SnnccError("a LIF population on Loihi receives one feed-forward and at most one recurrent projection",
                             field=f"node '{lif}'")
        for r in rec:
            if graph.port(lif, r) != "spikes":
                raise SnnccError("Loihi sends spikes, not voltages", field=f"edge {lif}->{r}")
        layers.append(ChainLayer(lif=lif, ff=dense, pre=pre, rec=rec[0] if rec else None))
        seen.add(lif)
        pre = lif
    if not layers:
        raise SnnccError("the graph has no LIF population to place on Loihi", field="graph")
    last = layers[-1].lif
    readers = graph.successors(last)
    readouts = [r for r in readers if isinstance(graph.node(r), Readout)]
    if len(readouts) != 1 or len(readers) != 1 + (1 if layers[-1].rec else 0):
        raise SnnccError("the last population must feed one Readout", field=f"node '{last}'")
    ro = graph.node(readouts[0])
    if ro.mode != "spike_count" or graph.port(last, readouts[0]) != "spikes" or graph.delay(last, readouts[0]) != 0:
        raise SnnccError("Loihi reads out spikes: the readout must count the last layer's spikes (mode spike_count, "
                         "no delay)", field=f"node '{readouts[0]}'")
    outs = [s for s in graph.successors(readouts[0]) if isinstance(graph.node(s), Output)]
    if len(outs) != 1 or graph.delay(readouts[0], outs[0]) != 0:
        raise SnnccError("the readout must feed one Output without delay", field=f"node '{readouts[0]}'")
    for name, op in graph.items():
        if isinstance(op, LIF) and name not in {c.lif for c in layers}:
            raise SnnccError("population not on the input-to-readout chain", field=f"node '{name}'")
    return layers


def lif_params_check(graph: Graph, layers: list[ChainLayer], allow_reset_change: bool) -> tuple[Graph, list[str]]:
    """Refuse subtract reset unless allowed (then lower it as reset to zero and say so)."""
    from snncc.targets.kit.graphs import change_reset

    return change_reset(graph, [c.lif for c in layers], from_="subtract", to="zero", allow=allow_reset_change,
                        refusal="Loihi 1 resets the voltage to zero and cannot reset by subtraction; pass "
                                "--allow-reset-change to deploy it with reset to zero (snncc check measures the cost)",
                        why="Loihi 1 cannot subtract")


def build_network(graph: Graph, layers: list[ChainLayer], quant: QuantizationRecord, timing: TimingRecord,
                  t_sample: int, metadata: dict[str, Any]) -> LoihiNetwork:
    """Register values of every layer from the quantization and timing records."""
    proj_q = {p.dense: p for p in quant.projections}
    layer_q = {lq.lif: lq for lq in quant.layers}
    extra = {(p.pre, p.dense): p.extra_delay for p in timing.projections}
    inp = graph.node(layers[0].pre)
    net_layers = [LoihiLayer(name=layers[0].pre, kind="input", n=inp.width)]
    for c in layers:
        op = graph.node(c.lif)
        pq, lq = proj_q[c.ff], layer_q[c.lif]
        layer = LoihiLayer(
            name=c.lif, kind="dense_rec" if c.rec else "dense", n=op.n,
            weight=pq.mantissas(graph.node(c.ff).weight)[0],
            wgt_exp=pq.exponents(graph.node(c.ff).weight),
            delay=int(extra[(c.pre, c.ff)]),
            v_th_mant=_register(lq.v_th_mant), i_decay=_register(lq.i_decay), v_decay=_register(lq.v_decay),
            ref_delay=timing.ref_delay[c.lif],
        )
        if c.rec:
            rq = proj_q[c.rec]
            w_rec = graph.node(c.rec).weight
            layer.weight_rec = rq.mantissas(w_rec)[0]
            layer.wgt_exp_rec = rq.exponents(w_rec)
            layer.delay_rec = int(extra[(c.lif, c.rec)])
        if lq.bias_mant is not None:
            layer.bias = np.asarray(lq.bias_mant, np.int64)
            layer.bias_exp = int(lq.bias_exp)
        net_layers.append(layer)
    for i, c in enumerate(layers, start=1):
        pq = proj_q[c.ff]
        terms = current_biases(graph, c.lif)
        columns = [(t.start, quantize_weights(t.vector, pq.scale, pq.exponents(t.vector))) for t in terms]
        bias_sources.attach(net_layers[i - 1], net_layers[i], timing.shifts.get(c.lif, 0), columns,
                            exponents=[pq.exponents(t.vector) for t in terms])
    return LoihiNetwork(layers=net_layers, t_sample=int(t_sample), metadata=dict(metadata))


def float_twin(network: LoihiNetwork, graph: Graph, layers: list[ChainLayer]) -> LoihiNetwork:
    """The lowered network with ``graph``'s float parameters in the integer registers' place.

    Chip units are dropped (w_chip = W, threshold = theta, decay = 4096 * (1 - alpha)), so
    ``emulator.reference_run(..., arithmetic="float")`` runs the lowered timing in exact float.
    The structure is the network's own: every delay, and the always-on bias sources (their
    columns carry the graph's float current biases; their voltage bias keeps its ratio to the
    threshold), so a wrong delay or source in the network fails the comparison with the IR.
    """
    base = network.layers[0]
    twin_layers = [LoihiLayer(name=base.name, kind="input", n=base.n, always_on=base.always_on)]
    for c, lay in zip(layers, network.layers[1:]):
        op = graph.node(c.lif)
        alpha, beta = op.decays(graph.dt)
        # per compartment: the model's neurons from the graph; bias sources keep their chip registers, with
        # threshold 1 and their voltage bias in units of their own chip threshold (so they fire as on chip)
        theta, i_dec, v_dec = (np.ones(lay.n) for _ in range(3))
        theta[:op.n] = op.threshold
        i_dec[:op.n], v_dec[:op.n] = chip.DECAY_ONE * (1.0 - alpha), chip.DECAY_ONE * (1.0 - beta)
        i_dec[op.n:] = np.broadcast_to(np.asarray(lay.i_decay, np.float64), (lay.n,))[op.n:]
        v_dec[op.n:] = np.broadcast_to(np.asarray(lay.v_decay, np.float64), (lay.n,))[op.n:]
        t = LoihiLayer(
            name=lay.name, kind=lay.kind, n=lay.n, weight=_twin_weight(graph, c, lay), wgt_exp=-chip.WEIGHT_SHIFT,
            delay=lay.delay, v_th_mant=theta / 2.0 ** chip.V_TH_SHIFT, i_decay=i_dec, v_decay=v_dec,
            ref_delay=lay.ref_delay, vmin=-math.inf, vmax=math.inf, always_on=lay.always_on,
        )
        if c.rec:
            t.weight_rec = np.zeros((lay.n, lay.n))
            t.weight_rec[:op.n, :op.n] = graph.node(c.rec).weight
            t.wgt_exp_rec = -chip.WEIGHT_SHIFT
            t.delay_rec = lay.delay_rec
        if (op.bias is not None and op.bias_placement == "voltage") or lay.always_on:
            t.bias, t.bias_exp = np.zeros(lay.n), 0
            if op.bias is not None and op.bias_placement == "voltage":
                t.bias[:op.n] = op.bias
            if lay.always_on:
                bias_chip = np.asarray(lay.bias[op.n:], np.float64) * 2.0 ** lay.bias_exp
                vth_chip = np.broadcast_to(np.asarray(lay.v_th_mant, np.float64), (lay.n,))[op.n:] * 2.0 ** chip.V_TH_SHIFT
                t.bias[op.n:] = bias_chip / vth_chip
        twin_layers.append(t)
    return LoihiNetwork(layers=twin_layers, t_sample=network.t_sample, metadata={})


def _register(value):
    """A register from the quantization record: an int, or a per-neuron list as an int array."""
    return value if isinstance(value, int) else np.asarray(value, np.int64)


def _twin_weight(graph: Graph, c: ChainLayer, lay: LoihiLayer) -> np.ndarray:
    """Float feed-forward weights shaped like the network's: the model's, then one column per bias source."""
    w = graph.node(c.ff).weight
    n = graph.node(c.lif).n
    terms = current_biases(graph, c.lif)
    sources = lay.weight.shape[1] - w.shape[1]
    repeats = sources // len(terms) if terms else 0
    if sources != repeats * len(terms) or (terms and not repeats):
        raise InternalError(f"check failed: {sources} bias-source columns for {len(terms)} current-bias terms",
                         field=f"layer '{lay.name}'")
    out = np.zeros(lay.weight.shape)
    out[:n, :w.shape[1]] = w
    for j, term in enumerate(terms):
        out[:n, w.shape[1] + j * repeats:w.shape[1] + (j + 1) * repeats] = term.vector[:, None]
    return out
