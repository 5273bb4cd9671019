"""A written bundle opened for measurement: read from its file, its populations named, and the
lowering's intermediate stages re-derived from the model so a check can break a loss down by cause.

What ``snncc check`` measures is always the network read from the file (``WrittenBundle.run``).
The stages before it -- the graph in the order Loihi runs, and with quantized parameters in float
-- exist only inside the compiler; they are re-derived by lowering the model again with the
options compile recorded in the bundle (``/snncc/metadata`` ``compile_options``) and used only if
that lowering reproduces the file's network exactly (every register, weight, exponent and delay).
Otherwise (a bundle from another snncc version, a netx or SLAYER file, an edited bundle) the
breakdown is left out and ``stages_note`` says why; the bundle is still measured against the model.

Population spikes are read from the run at their layer (relay layers included) and time shift
(``population_shifts``), so a relayed bundle reads like the network it relays. A replicated bundle
(``--replicas``, ``lowering/replicate.py``) reads like the model: its input relays are not a model
population, and a copied population is read as its first copy (the model's own neuron count).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.ir.graph import Graph
from snncc.targets.loihi.network import LoihiNetwork
from snncc.targets.loihi.options import STREAM_GAP
from snncc.targets.loihi.options import recorded as recorded_options

LAYER_FIELDS = ("kind", "n", "always_on", "weight", "weight_rec", "wgt_exp", "wgt_exp_rec", "delay", "delay_rec",
                "bias", "bias_exp", "v_th_mant", "i_decay", "v_decay", "ref_delay")


@dataclass
class WrittenBundle:
    path: str
    network: LoihiNetwork                # read from the file: what is measured
    populations: list[str]               # the model's LIF populations, in layer order
    layer_of: dict[str, int]             # population -> its layer in ``network`` (relay layers counted)
    shifts: dict[str, int]               # population -> steps its spikes appear later than in the IR
    output_shift: int
    lowered: Any = None                  # LoweredModel re-derived from the model (None: see stages_note)
    stages_note: str | None = None
    sizes: dict[str, int] | None = None  # population -> the model's neuron count (replicated bundles)

    def cut(self, spikes: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Population spikes cut to the model's neurons (a replicated population: its first copy)."""
        return {k: v[..., :self.sizes[k]] if self.sizes and k in self.sizes else v for k, v in spikes.items()}

    @property
    def metadata(self) -> dict[str, Any]:
        return self.network.metadata

    @property
    def steps(self) -> int:
        """The model's own sample length: tSample less the outputs' shift."""
        return int(self.network.t_sample - self.output_shift)

    def lead(self) -> int:
        return max([self.output_shift, *self.shifts.values()])

    def run(self, x: np.ndarray, *, mode: str = "batch", gap: int = STREAM_GAP):
        """(population spikes cut to the input's T, emulation result) of the file's network on ``x`` (B, T, C)."""
        from snncc.targets.loihi.emulation.emulator import emulate, pad

        steps = x.shape[1]
        kw = {"mode": "stream", "gap": int(gap)} if mode == "stream" else {}
        res = emulate(self.network, pad(x, self.lead()), record="all", **kw)
        out = {}
        for name in self.populations:
            j, s = self.layer_of[name], self.shifts.get(name, 0)
            out[name] = res.spikes[j][:, s:s + steps, :self.network.layers[j].model_n]
        return self.cut(out), res

    def run_wide(self, x: np.ndarray, *, mode: str = "batch", gap: int = STREAM_GAP) -> np.ndarray:
        """The output population's spikes (B, T, n) with wide registers (no wrap, no clip): what overflow costs."""
        from snncc.targets.loihi.emulation.emulator import emulate, pad

        kw = {"mode": "stream", "gap": int(gap)} if mode == "stream" else {}
        res = emulate(self.network, pad(x, self.lead()), wide=True, **kw)
        s = self.output_shift
        return res.output_spikes[:, s:s + x.shape[1], :self.network.layers[-1].model_n]


def same_network(a: LoihiNetwork, b: LoihiNetwork) -> str | None:
    """None when ``a`` and ``b`` hold the same registers, weights, exponents and delays; else the first difference."""
    if len(a.layers) != len(b.layers):
        return f"{len(a.layers)} layers against {len(b.layers)}"
    if a.t_sample != b.t_sample:
        return f"tSample {a.t_sample} against {b.t_sample}"
    for i, (x, y) in enumerate(zip(a.layers, b.layers)):
        for key in LAYER_FIELDS if i else ("kind", "n", "always_on"):
            u, v = getattr(x, key), getattr(y, key)
            if u is None or v is None:
                if (u is None) != (v is None):
                    return f"layer {i} {key}"
                continue
            if np.shape(u) != np.shape(v) and np.ndim(u) and np.ndim(v):
                return f"layer {i} {key}"
            if not np.array_equal(np.broadcast_to(np.asarray(u), np.shape(v) or np.shape(u)),
                                  np.broadcast_to(np.asarray(v), np.shape(u) or np.shape(v))):
                return f"layer {i} {key}"
    return None


def _names(network: LoihiNetwork, graph: Graph) -> tuple[list[str], dict[str, int]]:
    """The model's populations and their layers in ``network``, from the bundle's records, else by position."""
    from snncc.ir.nodes import LIF

    meta = network.metadata
    names = meta.get("layer_names")
    index = meta.get("relayed_layer_index") or list(range(len(network.layers)))
    lifs = set(graph.of_kind(LIF))
    relay = (meta.get("replication") or {}).get("relay")
    if isinstance(names, list) and len(names) == len(network.layers) and len(index) > 1:
        pairs = [(str(names[j]), int(j)) for j in index[1:] if str(names[j]) != relay]
        if {p for p, _ in pairs} <= lifs:
            return [p for p, _ in pairs], dict(pairs)
    from snncc.targets.kit.graphs import fold_linear
    from snncc.targets.loihi.lowering.registers import chain

    try:
        pops = [c.lif for c in chain(fold_linear(graph)[0])]
    except SnnccError:
        pops = []
    if len(pops) != len(network.layers) - 1:
        raise SnnccError(f"the bundle's {len(network.layers) - 1} layers do not line up with the model's "
                         f"{len(pops)} populations", field="layers")
    return pops, {p: i for i, p in enumerate(pops, start=1)}


def open_bundle(path: str | Path, graph: Graph) -> WrittenBundle:
    """The bundle at ``path`` read for measuring against ``graph``, with the lowering stages re-derived
    when the model lowers to exactly this bundle under the options compile recorded."""
    from snncc.targets.loihi.bundle.read import read_bundle

    network = read_bundle(path)
    try:
        pops, layer_of = _names(network, graph)
    except SnnccError as err:
        raise err.with_file(str(path)) from None
    meta = network.metadata
    shifts = {p: int(v) for p, v in (meta.get("population_shifts") or {}).items() if p in layer_of}
    from snncc.targets.loihi.lowering.replicate import model_sizes

    bundle = WrittenBundle(str(path), network, pops, layer_of, shifts, int(meta.get("output_shift", 0) or 0),
                           sizes=model_sizes(meta.get("replication")) or None)
    recorded = meta.get("compile_options")
    if not isinstance(recorded, dict):
        bundle.stages_note = ("the bundle records no compile options (not written by this snncc): the loss is not "
                              "broken down by cause; the bundle is measured against the model as a whole")
        return bundle
    try:
        lowered, relayed = relower(graph, recorded)
    except SnnccError as err:
        raise err.with_file(str(path)) from None
    finetuned = isinstance(meta.get("finetune"), dict) and bool(meta["finetune"].get("finetuned"))
    if finetuned and relayed is None:
        return _finetuned(bundle, lowered)
    difference = same_network(relayed if relayed is not None else lowered.network, network)
    if difference is not None:
        bundle.stages_note = (f"the model lowered with the bundle's recorded options gives another network "
                              f"({difference} differs; another snncc version?): the loss is not broken down by cause")
        return bundle
    bundle.lowered = lowered
    return bundle


STRUCTURE = ("kind", "n", "always_on", "delay", "delay_rec", "ref_delay")


def same_structure(a: LoihiNetwork, b: LoihiNetwork) -> str | None:
    """None when ``a`` and ``b`` have the same layers, sizes, bias sources, delays and refractory periods (what
    fine-tuning keeps; it trains weights, exponents, thresholds, decays and biases); else the first difference."""
    if len(a.layers) != len(b.layers) or a.t_sample != b.t_sample:
        return f"{len(a.layers)} layers, tSample {a.t_sample} against {len(b.layers)}, {b.t_sample}"
    for i, (x, y) in enumerate(zip(a.layers, b.layers)):
        for key in STRUCTURE if i else ("kind", "n", "always_on"):
            u, v = getattr(x, key), getattr(y, key)
            if np.shape(u) != np.shape(v) and np.ndim(u) and np.ndim(v):
                return f"layer {i} {key}"
            if not np.array_equal(np.broadcast_to(np.asarray(u), np.shape(v) or np.shape(u)),
                                  np.broadcast_to(np.asarray(v), np.shape(u) or np.shape(v))):
                return f"layer {i} {key}"
    return None


def _finetuned(bundle: WrittenBundle, lowered) -> WrittenBundle:
    """A fine-tuned bundle (``compile --finetune``): its registers are not the lowering's, by design. When its
    structure is the lowering's, the stages are the lowering's with (c) the fine-tuned registers read back in float
    (``finetune.export.adapted_graph``, what ``--finetune-out`` writes, checked against the bundle at compile)."""
    from snncc.targets.loihi.finetune.export import adapted_graph
    from snncc.targets.loihi.lowering.chip_units import in_chip_units

    problem = same_structure(lowered.network, bundle.network)
    if problem is not None:
        bundle.stages_note = (f"a fine-tuned bundle (--finetune) whose structure the model's lowering under the "
                              f"recorded options does not reproduce ({problem} differs): the loss is not broken "
                              "down by cause")
        return bundle
    lowered.quantized = in_chip_units(adapted_graph(lowered, bundle.network), lowered.quant_record)
    bundle.lowered = lowered
    bundle.stages_note = ("a fine-tuned bundle (--finetune): stage (c) is its fine-tuned registers read back in float "
                          "(the adapted graph --finetune-out writes), so the weights cause includes what fine-tuning "
                          "changed; the other stages are the lowering's")
    return bundle


def relower(graph: Graph, recorded: dict[str, Any]):
    """(LoweredModel, relayed network or None) of ``graph`` under compile's recorded options."""
    from snncc.targets.loihi.lowering.lower import lower_model
    from snncc.targets.loihi.mapping.relays import needs_relays, relay_network

    try:
        options = recorded_options(recorded)
    except SnnccError as err:       # an edited bundle: its recorded options are not ones compile takes
        raise SnnccError(f"compile_options: {err.field}: {err.rule}", field="/snncc/metadata") from None
    lowered = lower_model(graph, options)
    relayed = None
    if needs_relays(lowered.network):
        relayed = relay_network(lowered.network)[0]
    return lowered, relayed
