"""Which IR graphs Xylo can hold, as a chain of populations, and what the lowering reads from it.

    Input(spikes) -> Dense -> LIF [<- Dense <- same LIF] (-> Dense -> LIF [<- ...])* -> Readout(spike_count) -> Output

Every population but the last becomes hidden (reservoir) neurons; the last is the readout
population (Xylo's output neurons, or hidden proxies relayed to them). Conv layers reach here
already unrolled into Dense connection matrices (``snncc.passes.fold_linear``).
"""

from __future__ import annotations

from dataclasses import dataclass

from snncc.targets.kit import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LSTM, Dense, Input, Output, Readout


@dataclass(frozen=True)
class Population:
    lif: str
    ff: str            # the Dense feeding it from the previous population
    pre: str           # the previous population (the Input or a LIF)
    rec: str | None    # the Dense of its recurrent loop, if any


def _one_line(rule: str, field: str) -> SnnccError:
    return SnnccError(rule, field=field)


def populations(graph: Graph) -> list[Population]:
    """The populations of ``graph`` in order (input side first), or one line saying what Xylo cannot hold."""
    if graph.of_kind(LSTM):
        raise _one_line("an LSTM cannot run on Xylo (a spiking chip); compile it for --target jetson",
                        f"node '{graph.of_kind(LSTM)[0]}'")
    inputs = graph.of_kind(Input)
    if len(inputs) != 1:
        raise _one_line(f"the Xylo lowering needs exactly one Input, the graph has {len(inputs)}", "graph")
    if graph.node(inputs[0]).signal != "spikes":
        raise _one_line("Xylo's inputs are spike events; an analog input needs a spike encoder first",
                        f"node '{inputs[0]}'.signal")
    pops: list[Population] = []
    pre, seen = inputs[0], {inputs[0]}
    while True:
        is_lif = isinstance(graph.node(pre), LIF)
        ff = [s for s in graph.successors(pre) if isinstance(graph.node(s), Dense)
              and not (is_lif and pre in graph.successors(s))]
        if not ff:
            break
        if len(ff) > 1:
            raise _one_line("the Xylo lowering takes chains: a population may feed one next population", f"node '{pre}'")
        (dense,) = ff
        if graph.port(pre, dense) != "spikes":
            raise _one_line("Xylo neurons send spikes, not voltages", f"edge {pre}->{dense}")
        posts = graph.successors(dense)
        if len(posts) != 1 or not isinstance(graph.node(posts[0]), LIF):
            raise _one_line("on Xylo a Dense must feed exactly one LIF population", f"node '{dense}'")
        lif = posts[0]
        if lif in seen:
            raise _one_line("only self-recurrence (a LIF -> Dense -> same LIF loop) is supported", f"node '{lif}'")
        if is_lif and [s for s in graph.successors(pre) if isinstance(graph.node(s), Readout)]:
            raise _one_line("a hidden population cannot also feed the readout", f"node '{pre}'")
        rec = [d for d in graph.successors(lif) if isinstance(graph.node(d), Dense) and lif in graph.successors(d)]
        if len(rec) > 1:
            raise _one_line("at most one recurrent projection per population", f"node '{lif}'")
        if set(graph.predecessors(lif)) != {dense} | set(rec):
            raise _one_line("a population receives one feed-forward and at most one recurrent projection",
                            f"node '{lif}'")
        for r in rec:
            if graph.port(lif, r) != "spikes":
                raise _one_line("Xylo neurons send spikes, not voltages", f"edge {lif}->{r}")
            if len(graph.predecessors(r)) != 1:
                raise _one_line("a recurrent projection takes only its own population's spikes", f"node '{r}'")
        pops.append(Population(lif=lif, ff=dense, pre=pre, rec=rec[0] if rec else None))
        seen.add(lif)
        pre = lif
    if not pops:
        raise _one_line("the graph has no LIF population to place on Xylo", "graph")
    last = pops[-1].lif
    readouts = [r for r in graph.successors(last) if isinstance(graph.node(r), Readout)]
    others = [r for r in graph.successors(last) if r not in readouts and r != pops[-1].rec]
    if len(readouts) != 1 or others:
        raise _one_line("the last population must feed one Readout (and nothing else but its own loop)",
                        f"node '{last}'")
    ro = graph.node(readouts[0])
    if ro.mode != "spike_count" or graph.port(last, readouts[0]) != "spikes" or graph.delay(last, readouts[0]):
        raise _one_line("Xylo reads out spikes: the readout must count the last population's spikes "
                        "(mode spike_count, no delay)", f"node '{readouts[0]}'")
    outs = graph.successors(readouts[0])
    if len(outs) != 1 or not isinstance(graph.node(outs[0]), Output) or graph.delay(readouts[0], outs[0]):
        raise _one_line("the readout must feed one Output without delay", f"node '{readouts[0]}'")
    for name, op in graph.items():
        if isinstance(op, LIF) and name not in {p.lif for p in pops}:
            raise _one_line("population not on the input-to-readout chain", f"node '{name}'")
    return pops
