"""NIR graphs (``.nir``, the ``nir`` package) -> snncc IR.

NIR is continuous-time and stores neither a time step nor a reset mode. snncc discretises every
neuron with forward Euler at step ``dt``, current first, then voltage (what snnTorch does with
the graphs it exports), and records ``discretisation="euler"`` in each IR LIF.

CubaLIF (NIR):  tau_syn dI/dt = -I + w_in*S,   tau_mem dv/dt = (v_leak - v) + r*I,
                spike v > v_threshold, v <- v_reset.
Forward Euler at dt, with a = w_in*dt/tau_syn and m = r*dt/tau_mem (per neuron):
    I[t] = (1 - dt/tau_syn) I[t-1] + a S[t]
    v[t] = (1 - dt/tau_mem) v[t-1] + m I[t] + (dt/tau_mem) v_leak
With the IR current J = m*I this is exactly the IR LIF (alpha = 1 - dt/tau_syn,
beta = 1 - dt/tau_mem, V = v unchanged, threshold = v_threshold unchanged):
    J[t] = alpha J[t-1] + (a*m) S[t]          -> the gain g = a*m scales the rows of the incoming
                                                 weights AND biases (Affine biases stay on the
                                                 current: the Dense bias, filtered by alpha)
    V[t] = beta V[t-1] + J[t] + (dt/tau_mem) v_leak   -> a voltage bias (exact)
snnTorch exports r = tau_mem/dt and w_in = tau_syn/dt, so g = 1 there (|g - 1| <= 1e-9 is float
noise of that export and is snapped to exactly 1). v_reset != 0 is refused: the IR's V rests and
resets at 0 and starts at 0, so a shifted reset cannot be expressed exactly.
LIF/LI: the same with no synapse (IR tau_syn = dt, so alpha = 0 exactly), g = r*dt/tau.
IF/I: no leak (IR tau_mem = 1e30 s, so beta == 1.0 exactly in float64), g = r*dt.
Threshold: a memoryless comparator (tau_syn = tau_mem = dt: alpha = beta = 0, V = input).
LI, CubaLI and I never spike (threshold +inf) and send their voltage (edge port "voltage").

dt: ``--dt`` if given; else the ``snncc`` record of a graph snncc exported; else a ``dt`` key in
the graph's metadata; else inferred from the snnTorch convention r = tau_mem/dt (dt = tau_mem/r,
which must agree for every neuron and lie below every time constant) -- said in the graph's
``import_notes``; otherwise refused with a line asking for ``--dt``.
Norse's own LIF step updates the voltage from the PREVIOUS step's current and adds input spikes
to the current without the dt/tau_syn factor; snncc does not reproduce that order (a Norse export,
r = w_in = 1, needs ``--dt`` and is integrated as NIR's equations above).
Reset: ``--reset zero|subtract|zero-delayed``; default ``zero`` (NIR's own equation v <- v_reset = 0,
applied in the step of the spike, as the NIR paper's ``braille_noDelay_*`` graphs were trained:
snnTorch with reset_delay=False). snnTorch's
Synaptic/RSynaptic by default reset one step LATE: mem[t] = (beta*mem[t-1] + syn[t])*(1 - s[t-1]),
i.e. V is also held at 0 in the step after a spike -- exactly the IR's zero reset with refractory
2, which ``zero-delayed`` selects. snnTorch's late subtraction (mem[t] = beta*mem[t-1] + syn[t] -
thr*s[t-1]) has no exact IR form; ``subtract`` subtracts in the step of the spike.
Delays: a NIR ``Delay`` node becomes an IR edge delay of round(delay/dt) steps (non-integer or
per-neuron differing delays are refused). Every other edge is delay 0 (snnTorch and Norse
evaluate a feed-forward chain within one step), except that a cycle with no Delay node on it gets
delay 1 on the edge leaving its last neuron population before the loop closes -- snnTorch's
RSynaptic/RLeaky and Norse's recurrent cells feed back the PREVIOUS step's spikes.
Convolutional nodes (Conv1d, Conv2d, SumPool2d, AvgPool2d) become IR Conv nodes and Flatten is the
identity: ``frontends/nir_conv.py`` states the rules. A graph whose neurons are all IF/I (no time
constant) and that states no dt runs at dt = 1 (one NIR time unit per step), said in its notes.
Sub-graphs (nested NIRGraph nodes, edges addressed as ``sub`` or ``sub.node``) are flattened;
node names become dotted paths (snnTorch's RSynaptic sub-graph "lif1" gives "lif1.lif", "lif1.w_rec").
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from snncc.errors import SnnccError
from snncc.frontends import nir_conv
from snncc.limits import check_real
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, RESETS, Conv, Dense, Input, Output, Readout

SNNCC_KEY = "snncc"          # graph-metadata key of the record snncc's exporter writes
RECORD_FORMAT = "snncc-nir"
GAIN_SNAP = 1e-9             # |gain - 1| below this is float noise of an r = tau/dt export
NO_LEAK_TAU = 1e30           # IF/I: 1 - dt/1e30 == 1.0 exactly in float64
SUPPORTED = ("Input", "Output", "Affine", "Linear", "Scale", "Delay", "Flatten", "LIF", "CubaLIF",
             "LI", "CubaLI", "I", "IF", "Threshold", "NIRGraph") + nir_conv.KINDS
PASS_THROUGH = ("Delay", "Flatten", "SubInput", "SubOutput")
RESET_CHOICES = RESETS + ("zero-delayed",)   # zero-delayed: snnTorch's default late zero reset


@dataclass
class _Flat:
    """A NIR graph with sub-graphs flattened: primitive nodes by dotted path, edges between them."""

    nodes: dict[str, Any] = field(default_factory=dict)
    kinds: dict[str, str] = field(default_factory=dict)
    edges: list[tuple[str, str]] = field(default_factory=list)


def _kind(node: Any) -> str:
    return type(node).__name__


def _join(prefix: str, name: str) -> str:
    """Dotted path of ``name`` inside the sub-graph ``prefix`` ("lif1."); keys that already carry the
    sub-graph's name (snnTorch/NIR-paper helpers write "lif1.lif" inside "lif1") are not doubled."""
    last = prefix[:-1].rsplit(".", 1)[-1] if prefix else ""
    if last and name.startswith(last + "."):
        return prefix[: -(len(last) + 1)] + name
    return prefix + name


def _flatten(graph: Any, prefix: str, flat: _Flat, top: bool) -> None:
    import nir

    for name, node in graph.nodes.items():
        path = _join(prefix, str(name))
        if path in flat.nodes or path in flat.kinds:
            raise SnnccError("two NIR nodes flatten to the same name", field=f"node '{path}'")
        if "/" in path:
            raise SnnccError("NIR node names must not contain '/'", field=f"node '{path}'")
        if isinstance(node, nir.NIRGraph):
            _flatten(node, path + ".", flat, top=False)
            continue
        kind = _kind(node)
        if not top and kind in ("Input", "Output"):
            kind = "Sub" + kind
        flat.nodes[path] = node
        flat.kinds[path] = kind
    for src, dst in graph.edges:
        flat.edges.append((_endpoint(graph, prefix, str(src), "source"), _endpoint(graph, prefix, str(dst), "destination")))


def _endpoint(graph: Any, prefix: str, name: str, role: str) -> str:
    """Resolve an edge end inside ``graph``: a node, a sub-graph (its single Input/Output) or ``sub.node``."""
    import nir

    if name in graph.nodes:
        node = graph.nodes[name]
        if isinstance(node, nir.NIRGraph):
            want = nir.Output if role == "source" else nir.Input
            ends = [k for k, n in node.nodes.items() if isinstance(n, want)]
            if len(ends) != 1:
                raise SnnccError(f"an edge {'leaves' if role == 'source' else 'enters'} sub-graph '{_join(prefix, name)}', "
                                 f"which has {len(ends)} {want.__name__} nodes (need exactly 1)",
                                 field=f"node '{_join(prefix, name)}'")
            return _endpoint(node, _join(prefix, name) + ".", ends[0], role)
        return _join(prefix, name)
    head, _, rest = name.partition(".")
    if rest and head in graph.nodes and isinstance(graph.nodes[head], nir.NIRGraph):
        sub = graph.nodes[head]
        inner = name if name in sub.nodes else rest   # "lif1.lif" may be the key inside "lif1" itself
        return _endpoint(sub, _join(prefix, head) + ".", inner, role)
    raise SnnccError(f"edge {role} '{name}' is not a node of the graph", field=f"edges of '{prefix or '<top>'}'")


def _arr(node: Any, attr: str, name: str) -> np.ndarray:
    value = getattr(node, attr, None)
    if value is None:
        raise SnnccError(f"missing parameter {attr}", field=f"node '{name}'.{attr}")
    check_real(value, field=f"node '{name}'.{attr}")
    arr = np.asarray(value, dtype=np.float64).reshape(-1)
    if not np.all(np.isfinite(arr)) and attr not in ("v_threshold", "threshold"):
        raise SnnccError("contains NaN or Inf", field=f"node '{name}'.{attr}")
    return arr


def _record(nir_graph: Any) -> dict[str, Any] | None:
    """The snncc export record stored in the graph metadata, if any."""
    meta = getattr(nir_graph, "metadata", None) or {}
    raw = meta.get(SNNCC_KEY) if isinstance(meta, dict) else None
    if raw is None:
        return None
    if isinstance(raw, bytes):
        raw = raw.decode("utf-8")
    try:
        rec = json.loads(str(raw))
    except ValueError:
        raise SnnccError("metadata entry 'snncc' is not valid JSON", field="metadata.snncc") from None
    if not isinstance(rec, dict) or rec.get("format") != RECORD_FORMAT:
        raise SnnccError(f"metadata entry 'snncc' is not a {RECORD_FORMAT} record", field="metadata.snncc")
    return rec


# -- dt ------------------------------------------------------------------------------------------
STEPS_PER_TIME_CONSTANT = 10     # forward Euler: dt/tau = 0.1 keeps the decay 1 - dt/tau close to exp(-dt/tau)
SNNTORCH_EXPORT_DT = 1e-4        # the step snnTorch's NIR export assumes unless told otherwise


def _nice_below(x: float) -> float:
    """The largest 1, 2 or 5 x 10^k not above ``x``."""
    exp = math.floor(math.log10(x))
    return max(m * 10.0 ** exp for m in (1, 2, 5) if m * 10.0 ** exp <= x * (1 + 1e-9))


def dt_suggestion(taus: list[np.ndarray], ratios: list[np.ndarray]) -> str:
    """What the graph's time constants suggest for --dt: the step that makes the shortest one
    ``STEPS_PER_TIME_CONSTANT`` steps, and snnTorch's export step where r = tau_mem/dt holds with it."""
    finite = [float(t) for arr in taus for t in np.asarray(arr, dtype=float).reshape(-1) if np.isfinite(t) and t > 0]
    if not finite:
        return "pass --dt (the step the graph was trained at)"
    shortest = min(finite)
    step = _nice_below(shortest / STEPS_PER_TIME_CONSTANT)
    text = (f"the shortest time constant is {shortest:g} s: try --dt={step:g} (it spans {shortest / step:g} steps; "
            "forward Euler needs dt well below every time constant), or the step the graph was trained at")
    fits = [np.all(np.isclose(np.asarray(r, dtype=float), SNNTORCH_EXPORT_DT, rtol=1e-6, atol=0)) for r in ratios]
    if any(fits) and SNNTORCH_EXPORT_DT < shortest:
        text += f"; --dt={SNNTORCH_EXPORT_DT:g} (snnTorch's export step) makes r = tau_mem/dt hold for some neurons"
    return text


def infer_dt(flat: _Flat) -> float:
    """dt from the snnTorch convention r = tau_mem/dt, consistent over every (Cuba)LIF/LI neuron."""
    candidates, taus = [], []
    for name, kind in flat.kinds.items():
        node = flat.nodes[name]
        if kind in ("CubaLIF", "CubaLI"):
            tau_mem = _arr(node, "tau_mem", name)
            named = {"tau_mem": tau_mem, "tau_syn": _arr(node, "tau_syn", name)}
        elif kind in ("LIF", "LI"):
            tau_mem = _arr(node, "tau", name)
            named = {"tau": tau_mem}
        else:
            continue
        for label, tau in named.items():   # before any division by them
            if np.any(tau <= 0):
                raise SnnccError("time constants must be positive", field=f"node '{name}'.{label}")
        taus += list(named.values())
        r = _arr(node, "r", name)
        with np.errstate(divide="ignore", invalid="ignore"):
            candidates.append((name, tau_mem / r))
    if not candidates:
        raise SnnccError("NIR stores no time step and this graph has no leaky neuron to infer one from "
                         "(snnTorch convention r = tau_mem/dt); pass --dt (the step the graph was trained at)",
                         field="dt")
    hint = dt_suggestion(taus, [values for _, values in candidates])
    ref = candidates[0][1].reshape(-1)[0]
    for name, values in candidates:
        if not (np.all(np.isfinite(values)) and np.all(values > 0) and np.allclose(values, ref, rtol=1e-6, atol=0)):
            raise SnnccError("cannot infer dt: r/tau_mem differs between neurons, so the graph does not follow "
                             f"the snnTorch convention r = tau_mem/dt; {hint}", field=f"node '{name}'.r")
    dt = float(f"{float(ref):.12g}")
    for name, tau in _time_constants(flat):     # a step as long as a time constant leaves no memory: another model
        shortest = float(np.min(tau))
        if dt >= shortest * (1 - MEMORY_TOLERANCE):
            raise SnnccError(f"cannot infer dt: r = tau/dt gives dt = {dt:g} s, which is not below this population's "
                             f"time constant ({shortest:g} s): it would keep no state from one step to the next "
                             f"(r = 1 is Norse's convention, not snnTorch's); {hint}", field=f"node '{name}'")
    return dt


MEMORY_TOLERANCE = 1e-6      # relative: a float32 tau equal to dt up to rounding counts as equal


def _time_constants(flat: _Flat) -> list[tuple[str, np.ndarray]]:
    """(node, its time constants) of every leaky neuron node, in the graph's order."""
    out = []
    for name, kind in flat.kinds.items():
        node = flat.nodes[name]
        if kind in ("CubaLIF", "CubaLI"):
            out.append((name, np.concatenate([_arr(node, "tau_mem", name).reshape(-1),
                                              _arr(node, "tau_syn", name).reshape(-1)])))
        elif kind in ("LIF", "LI"):
            out.append((name, _arr(node, "tau", name).reshape(-1)))
    return out


def _graph_meta_dt(nir_graph: Any) -> float | None:
    meta = getattr(nir_graph, "metadata", None) or {}
    if isinstance(meta, dict) and "dt" in meta:
        try:
            return float(np.asarray(meta["dt"]).reshape(-1)[0])
        except (TypeError, ValueError, IndexError):
            raise SnnccError("metadata 'dt' is not a number", field="metadata.dt") from None
    return None


# -- nodes ---------------------------------------------------------------------------------------
@dataclass
class _Neuron:
    lif: LIF
    gain: np.ndarray
    port: str


def _neuron(name: str, kind: str, node: Any, dt: float, reset: str, check_step: bool = True) -> _Neuron:
    """An IR LIF for a NIR neuron node, and the gain to fold into its incoming weights."""
    spiking = kind in ("CubaLIF", "LIF", "IF", "Threshold")
    if kind == "Threshold":
        thr = _arr(node, "threshold", name)
        return _Neuron(LIF(n=thr.size, tau_syn=dt, tau_mem=dt, threshold=thr, reset="zero",
                           discretisation="euler"), np.ones(thr.size), "spikes")
    r = _arr(node, "r", name)
    n = r.size
    if spiking:
        v_reset = _arr(node, "v_reset", name) if getattr(node, "v_reset", None) is not None else np.zeros(n)
        if np.any(v_reset != 0):
            raise SnnccError("v_reset != 0 cannot be expressed exactly (the IR's membrane starts, rests and "
                             "resets at 0)", field=f"node '{name}'.v_reset")
        threshold = _arr(node, "v_threshold", name)
        if np.any(np.isnan(threshold)):
            raise SnnccError("contains NaN", field=f"node '{name}'.v_threshold")
    else:
        threshold = np.full(n, np.inf)
    v_leak = np.zeros(n)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):   # a zero tau is refused just below
        if kind in ("CubaLIF", "CubaLI"):
            tau_syn, tau_mem = _arr(node, "tau_syn", name), _arr(node, "tau_mem", name)
            w_in = _arr(node, "w_in", name) if getattr(node, "w_in", None) is not None else np.ones(n)
            gain = (w_in * dt / tau_syn) * (r * dt / tau_mem)
            v_leak = _arr(node, "v_leak", name)
        elif kind in ("LIF", "LI"):
            tau_mem = _arr(node, "tau", name)
            tau_syn = np.full(n, dt)
            gain = r * dt / tau_mem
            v_leak = _arr(node, "v_leak", name)
        else:  # IF, I
            tau_syn, tau_mem = np.full(n, dt), np.full(n, NO_LEAK_TAU)
            gain = r * dt
    for label, tau in (("tau_syn", tau_syn), ("tau" if kind in ("LIF", "LI") else "tau_mem", tau_mem)):
        if np.any(tau <= 0):
            raise SnnccError("time constants must be positive", field=f"node '{name}'.{label}")
        if check_step and np.any(dt > tau):
            raise SnnccError(f"dt = {dt:g} s exceeds a time constant ({float(np.min(tau)):g} s): forward Euler "
                             "would give a negative decay; use a smaller --dt", field=f"node '{name}'.{label}")
    gain = np.where(np.abs(gain - 1.0) <= GAIN_SNAP, 1.0, gain)
    if np.any(gain == 0) or not np.all(np.isfinite(gain)):
        raise SnnccError("r and w_in must be non-zero and finite", field=f"node '{name}'.r")
    bias = None
    if np.any(v_leak != 0):
        bias = v_leak * dt / tau_mem
    delayed = spiking and reset == "zero-delayed"
    lif = LIF(n=n, tau_syn=tau_syn, tau_mem=tau_mem, threshold=threshold,
              reset=reset if spiking and not delayed else "zero", refractory=2 if delayed else 1,
              discretisation="euler", bias=bias, bias_placement="voltage")
    return _Neuron(lif, gain, "spikes" if spiking else "voltage")


def _delay_steps(name: str, node: Any, dt: float) -> int:
    delay = _arr(node, "delay", name)
    if delay.size == 0 or np.any(delay != delay[0]):
        raise SnnccError("per-channel delays differ; the IR has one delay per edge", field=f"node '{name}'.delay")
    steps = float(delay[0]) / dt
    if steps < 0 or abs(steps - round(steps)) > 1e-6 * max(1.0, abs(steps)):
        raise SnnccError(f"delay {float(delay[0]):g} s is not a whole number of steps of dt = {dt:g} s",
                         field=f"node '{name}'.delay")
    return int(round(steps))


# -- assembly ------------------------------------------------------------------------------------
class _Builder:
    """Turns a flattened NIR graph into IR nodes and delayed edges."""

    def __init__(self, flat: _Flat, dt: float, reset: str, check_step: bool = True):
        self.flat, self.dt, self.reset, self.check_step = flat, dt, reset, check_step
        self.ops: dict[str, Any] = {}
        self.ports: dict[str, str] = {}
        self.gains: dict[str, np.ndarray] = {}
        self.through: dict[str, int] = {}   # pass-through node -> its delay in steps
        self.edges: dict[tuple[str, str], int] = {}

    def nodes(self) -> None:
        for name, kind in self.flat.kinds.items():
            node = self.flat.nodes[name]
            if kind not in SUPPORTED and kind not in PASS_THROUGH:
                raise SnnccError(f"NIR node type {kind} is not supported by snncc (flat networks of "
                                 f"{', '.join(k for k in SUPPORTED if k != 'NIRGraph')} only)", field=f"node '{name}'")
            if kind in ("Input", "Output") and (getattr(node, "input_type" if kind == "Input" else "output_type", None) or {}).get(
                    "input" if kind == "Input" else "output") is None:
                raise SnnccError("the node has no shape", field=f"node '{name}'")
            if kind == "Input":
                width = int(np.prod(np.asarray(node.input_type["input"]).reshape(-1)))
                self.ops[name] = Input(width=width, signal="spikes")
            elif kind == "Output":
                width = int(np.prod(np.asarray(node.output_type["output"]).reshape(-1)))
                self.ops[name] = Output(width=width)
            elif kind in ("Affine", "Linear"):
                check_real(node.weight, field=f"node '{name}'.weight")
                if kind == "Affine" and node.bias is not None:
                    check_real(node.bias, field=f"node '{name}'.bias")
                w = np.asarray(node.weight, dtype=np.float64)
                if w.ndim != 2:
                    raise SnnccError(f"weight must be 2-D (out, in), got shape {w.shape}", field=f"node '{name}'.weight")
                bias = None
                if kind == "Affine" and node.bias is not None:
                    bias = np.broadcast_to(np.asarray(node.bias, dtype=np.float64), (w.shape[0],)).copy()
                self.ops[name] = Dense(weight=w, bias=bias)
            elif kind == "Scale":
                self.ops[name] = Dense(weight=np.diag(_arr(node, "scale", name)))
            elif kind in nir_conv.KINDS:
                self.ops[name] = nir_conv.convert(name, kind, node, self.flat.nodes, self.flat.kinds, self._preds())
            elif kind == "Delay":
                self.through[name] = _delay_steps(name, node, self.dt)
            elif kind in ("Flatten", "SubInput", "SubOutput"):
                self.through[name] = 0
            else:
                neuron = _neuron(name, kind, node, self.dt, self.reset, self.check_step)
                self.ops[name], self.ports[name], self.gains[name] = neuron.lif, neuron.port, neuron.gain

    def _preds(self) -> dict[str, list[str]]:
        preds: dict[str, list[str]] = {}
        for u, v in self.flat.edges:
            preds.setdefault(v, []).append(u)
        return preds

    def contract(self) -> None:
        """Edges between IR nodes, summing the delays of the pass-through nodes on each path."""
        succ: dict[str, list[str]] = {}
        for u, v in self.flat.edges:
            succ.setdefault(u, []).append(v)

        def reach(node: str, delay: int, seen: tuple[str, ...]) -> list[tuple[str, int]]:
            out = []
            for v in succ.get(node, []):
                if v in self.through:
                    if v in seen:
                        raise SnnccError("a cycle runs through pass-through nodes only", field=f"node '{v}'")
                    out += reach(v, delay + self.through[v], seen + (v,))
                else:
                    out.append((v, delay))
            return out

        for u in self.ops:
            for v, d in reach(u, 0, ()):
                if (u, v) in self.edges:
                    raise SnnccError(f"two paths connect '{u}' to '{v}'; the IR has one edge per pair", field=f"node '{v}'")
                self.edges[(u, v)] = d

    def fold_scales(self) -> None:
        """A Scale right after an Affine/Linear that feeds only it becomes part of that Dense."""
        for name, kind in self.flat.kinds.items():
            if kind != "Scale" or name not in self.ops:
                continue
            preds = [u for (u, v) in self.edges if v == name]
            if len(preds) != 1 or self.edges[(preds[0], name)] != 0:
                continue
            (p,) = preds
            if not isinstance(self.ops[p], Dense) or self.flat.kinds.get(p) == "Scale":
                continue
            if [v for (u, v) in self.edges if u == p] != [name]:
                continue
            s = np.diag(self.ops[name].weight)
            dense = self.ops[p]
            self.ops[p] = Dense(weight=s[:, None] * dense.weight, bias=None if dense.bias is None else s * dense.bias)
            del self.edges[(p, name)]
            for (u, v), d in list(self.edges.items()):
                if u == name:
                    del self.edges[(u, v)]
                    self.edges[(p, v)] = d
            del self.ops[name]

    def fold_gains(self) -> None:
        """Scale the rows of each neuron population's incoming weights and biases by its gain."""
        for name, gain in self.gains.items():
            if np.all(gain == 1.0):
                continue
            for (u, v), d in list(self.edges.items()):
                if v != name:
                    continue
                op = self.ops[u]
                sole = [w for (x, w) in self.edges if x == u] == [name]
                scaled = nir_conv.scaled_rows(op, gain) if isinstance(op, Conv) and sole else None
                if isinstance(op, Dense) and sole:
                    self.ops[u] = Dense(weight=gain[:, None] * op.weight, bias=None if op.bias is None else gain * op.bias)
                elif scaled is not None:
                    self.ops[u] = scaled
                else:
                    gname = f"{name}.gain_from_{u}"
                    self.ops[gname] = Dense(weight=np.diag(gain))
                    del self.edges[(u, v)]
                    self.edges[(u, gname)] = d
                    self.edges[(gname, name)] = 0
                    self.ports[gname] = "spikes"

    def move_delays_before_dense(self) -> None:
        """population -d-> Dense(no bias) -0-> X: the IR convention puts d on the edge into the Dense."""
        for name, op in self.ops.items():
            if not isinstance(op, Dense) or op.bias is not None:
                continue
            ins = [(u, d) for (u, v), d in self.edges.items() if v == name]
            outs = [(v, d) for (u, v), d in self.edges.items() if u == name]
            if len(ins) == 1 and len(outs) == 1 and outs[0][1] > 0:
                self.edges[(ins[0][0], name)] += outs[0][1]
                self.edges[(name, outs[0][0])] = 0

    def recurrent_delays(self) -> list[str]:
        """A cycle without delay gets 1 step on the edge leaving its last population (previous step's spikes)."""
        succ: dict[str, list[str]] = {n: [] for n in self.ops}
        for (u, v) in self.edges:
            succ[u].append(v)
        state: dict[str, int] = {}
        stack: list[str] = []
        placed: list[str] = []

        def visit(u: str) -> None:
            state[u] = 1
            stack.append(u)
            for v in succ[u]:
                if state.get(v) == 1:  # back edge u -> v closes the cycle stack[v:] + v
                    cycle = stack[stack.index(v):] + [v]
                    pairs = list(zip(cycle[:-1], cycle[1:]))
                    if sum(self.edges[p] for p in pairs) == 0:
                        for a, b in reversed(pairs):
                            if isinstance(self.ops[a], LIF):
                                self.edges[(a, b)] = 1
                                placed.append(f"{a}->{b}")
                                break
                elif v not in state:
                    visit(v)
            stack.pop()
            state[u] = 2

        roots = [n for n, op in self.ops.items() if isinstance(op, Input)]
        for root in roots + list(self.ops):
            if root not in state:
                visit(root)
        return placed


def _topological(b: _Builder) -> list[str]:
    """Node order: inputs first, then along the zero-delay edges (NIR's order breaks ties)."""
    import networkx as nx

    index = {name: i for i, name in enumerate(b.ops)}
    zero = nx.DiGraph()
    zero.add_nodes_from(b.ops)
    zero.add_edges_from(e for e, d in b.edges.items() if d == 0)
    if not nx.is_directed_acyclic_graph(zero):
        return list(b.ops)  # validate() names the algebraic loop
    return list(nx.lexicographical_topological_sort(zero, key=lambda n: (not isinstance(b.ops[n], Input), index[n])))


def _readout(g: Graph) -> str | None:
    """Insert a spike-count (or membrane-max) Readout before the single Output fed by a population."""
    outs = g.of_kind(Output)
    if len(outs) != 1:
        return None
    (out,) = outs
    preds = g.predecessors(out)
    if len(preds) != 1 or not isinstance(g.node(preds[0]), LIF) or "readout" in g:
        return None
    src = preds[0]
    port, delay = g.port(src, out), g.delay(src, out)
    mode = "spike_count" if port == "spikes" else "membrane_max"
    out_op = g.node(out)
    g.nx.remove_node(out)  # re-added after the readout to keep the node order causal
    g.add("readout", Readout(width=out_op.size, mode=mode))
    g.add(out, out_op)
    g.connect(src, "readout", delay=delay, port=port)
    g.connect("readout", out)
    return mode


def graph_from_nir(nir_graph: Any, dt: float | None = None, reset: str | None = None, source: str = "<nir>") -> Graph:
    """An IR graph from an in-memory ``nir.NIRGraph`` (see the module docstring for the rules)."""
    import nir

    if not isinstance(nir_graph, nir.NIRGraph):
        raise SnnccError(f"expected a NIR graph, got a single {type(nir_graph).__name__} node", field="node")
    if reset is not None and reset not in RESET_CHOICES:
        raise SnnccError(f"reset must be one of {', '.join(RESET_CHOICES)}, got {reset!r}", field="--reset")
    record = _record(nir_graph)
    flat = _Flat()
    _flatten(nir_graph, "", flat, top=True)
    notes: list[str] = []

    if record is not None:
        step = float(record["export_dt"])
        notes.append(f"snncc export record found: restoring the IR exactly (dt = {record['dt']:g} s)")
    elif dt is not None:
        step = float(dt)
    elif _graph_meta_dt(nir_graph) is not None:
        step = _graph_meta_dt(nir_graph)
        notes.append(f"dt = {step:g} s taken from the graph's metadata")
    elif nir_conv.non_leaky_only(flat.kinds):
        step = 1.0
        notes.append(nir_conv.NON_LEAKY_DT_NOTE)
    else:
        step = infer_dt(flat)
        notes.append(f"dt = {step:g} s inferred from the snnTorch convention r = tau_mem/dt (pass --dt to override)")
    if not (math.isfinite(step) and step > 0):
        raise SnnccError(f"dt must be a positive number of seconds, got {step}", field="dt")
    reset_mode = reset or "zero"
    if record is None:
        if reset is None:
            notes.append("reset: NIR cannot say whether a reset subtracts; using 'zero' in the step of the spike "
                         "(NIR's v <- v_reset); pass --reset subtract for a subtract-reset model, or --reset "
                         "zero-delayed for snnTorch's default late zero reset")
        elif reset == "zero-delayed":
            notes.append("reset: snnTorch's late zero reset = reset to zero plus V held at 0 for the next step "
                         "(refractory 2)")
        notes.append("discretisation: forward Euler, current then voltage (snnTorch's order), recorded as 'euler'")

    b = _Builder(flat, step, reset_mode, check_step=record is None)
    b.nodes()
    b.contract()
    b.fold_scales()
    b.fold_gains()
    if record is None:
        b.move_delays_before_dense()
    placed = b.recurrent_delays()
    if placed and record is None:
        notes.append("recurrent edges take the previous step's output (delay 1, as snnTorch/Norse): " + ", ".join(placed))

    g = Graph(step, name=Path(source).stem if source != "<nir>" else "nir", metadata={})
    for name in _topological(b):
        g.add(name, b.ops[name])
    for (u, v), d in b.edges.items():
        port = b.ports.get(u, "spikes") if isinstance(b.ops[u], LIF) else "spikes"
        g.connect(u, v, delay=d, port=port)
    if record is not None:
        from snncc.exporters.nir import restore_from_record

        g = restore_from_record(g, record, dt=dt, reset=reset)
        if dt is not None:
            notes.append(f"dt overridden by --dt = {dt:g} s")
        if reset is not None:
            notes.append(f"reset overridden by --reset {reset}")
    else:
        mode = _readout(g)
        widths = [g.node(n).size for n in g.of_kind(Input)]
        g.metadata.update({
            "source_format": "nir", "model_kind": "nir", "update_order": "nir-euler",
            "dt_source": "--dt" if dt is not None else ("metadata" if _graph_meta_dt(nir_graph) is not None else "inferred"),
            "reset": reset_mode, "discretisation": "euler", "input_copies": 1,
            "base_inputs": widths[0] if len(widths) == 1 else None,
        })
        if mode:
            g.metadata["readout"] = mode
            notes.append(f"readout: argmax of the output population's {'spike count' if mode == 'spike_count' else 'maximum voltage'}")
    g.metadata["import_notes"] = notes
    return g


def _group_type(group: Any) -> str:
    try:
        value = group["type"][()] if "type" in group else b""
    except (KeyError, OSError, RuntimeError, ValueError, TypeError):   # damaged: nir.read reports it
        return ""
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


def check_graph_groups(f: Any, path: str) -> None:
    """A NIR file stores its graph in the group ``/node``, a NIRGraph with a ``nodes`` and an ``edges``
    part, and so does each sub-graph. A missing part is refused in one line (nir.read's own message is
    a Python KeyError's)."""
    import h5py

    node = f.get("node") if isinstance(f, h5py.Group) else None
    if not isinstance(node, h5py.Group):
        raise SnnccError("missing: a NIR file stores its graph in the group /node", file=path, field="/node")
    pending = [node]
    while pending:
        group = pending.pop()
        if _group_type(group) != "NIRGraph":
            continue
        for part in ("nodes", "edges"):
            if part not in group:
                raise SnnccError(f"missing: a NIR graph lists its {part} in {group.name}/{part}", file=path,
                                 field=f"{group.name}/{part}")
        nodes = group["nodes"]
        if isinstance(nodes, h5py.Group):
            pending.extend(child for child in nodes.values() if isinstance(child, h5py.Group))


def check_declared_sizes(path: Path) -> None:
    """Refuse a NIR file whose HDF5 datasets declare more bytes than fit in memory, before nir.read
    allocates them (a small file can declare a huge dataset that is never written)."""
    import h5py

    from snncc.hdf5_links import check_self_contained
    from snncc.limits import check_memory

    try:
        f = h5py.File(path, "r")
    except (OSError, RuntimeError, ValueError):
        return   # nir.read reports what the file is not
    with f:
        check_self_contained(f, str(path))   # no link or dataset may lead to another file
        check_graph_groups(f, str(path))     # /node with its nodes and edges, before nir.read
        try:
            nir_conv.check_raw_fields(f)     # a stride of 0 would divide by zero inside nir.read
        except SnnccError as err:
            raise err.with_file(str(path)) from None
        sizes: list[tuple[str, int]] = []
        try:
            f.visititems(lambda key, obj: sizes.append((key, int(obj.size) * obj.dtype.itemsize))
                         if isinstance(obj, h5py.Dataset) else None)
        except (KeyError, OSError, RuntimeError, ValueError, TypeError) as err:   # damaged object headers
            raise SnnccError(f"damaged HDF5 structure ({type(err).__name__}: {err})", file=str(path),
                             field="format") from None
    for key, n_bytes in sizes:
        check_memory(n_bytes, f"the declared dataset /{key}", file=str(path), field=f"/{key}")
    check_memory(sum(n for _, n in sizes), "the file's declared datasets together", file=str(path), field="/")


def load(path: Path, options: Any) -> Graph:
    """Frontend entry for ``.nir`` files (``load_model`` validates the result)."""
    import nir

    from snncc.frontends.load_options import refuse_options

    refuse_options(options, ("dt", "reset"), "a NIR graph", path)
    check_declared_sizes(path)
    legacy_notes: list[str] = []
    try:
        nir_graph = nir.read(str(path), type_check=False)
    except Exception as ex:  # the nir/h5py readers raise assorted types on damaged files
        from snncc.frontends.nir_legacy import LegacyFileLacks, read_legacy

        detail = str(ex).strip().splitlines()[0] if str(ex).strip() else type(ex).__name__
        try:
            nir_graph, legacy_notes = read_legacy(path)   # an older NIR file whose meaning is unambiguous
        except LegacyFileLacks:
            raise
        except SnnccError:
            raise SnnccError(f"not a readable NIR graph ({detail})", file=str(path), field="format") from None
    try:
        g = graph_from_nir(nir_graph, dt=options.dt, reset=options.reset, source=str(path))
        g.metadata["import_notes"] = legacy_notes + list(g.metadata.get("import_notes", []))
        return g
    except (ValueError, TypeError, AttributeError, KeyError, IndexError) as ex:  # malformed node fields
        detail = str(ex).strip().splitlines()[0] if str(ex).strip() else type(ex).__name__
        raise SnnccError(f"malformed NIR graph ({type(ex).__name__}: {detail})", file=str(path), field="graph") from None
