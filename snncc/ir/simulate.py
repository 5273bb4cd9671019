"""The reference simulator: the single definition of what an IR graph computes.

Batched and vectorised in numpy, float64 (or float32). One time step t evaluates every node in
the topological order of the zero-delay edges; an edge with delay d delivers its source's
output of step t - d (zeros before t = 0). Node equations are those in ``snncc.ir.nodes``:

    LIF:  I = alpha*I + sum(in) (+b_I);  V = beta*V + I (+b_V);  V = 0 while refractory;
          s = V > theta;  V <- 0 | V - theta where s;  refractory counter <- r - 1 where s
          (spike rule max_spikes m / fire_test: s = min(m, floor(V/theta)) on V >= theta, or
          min(m, ceil(V/theta) - 1) on V > theta; V <- 0 | V - s*theta where s > 0)
    LSTM: PyTorch's cell, gate order i, f, g, o

    Dense: y = W x (+b);  Conv: the convolution on the C-order flattened map, as its connection matrix
           (``snncc.ir.conv.conv_matrix``: y = A x + bias)

Parts of the graph fed only by inputs through linear nodes (Dense, Conv; no state) are computed
for the whole sequence at once before the time loop. Results are numpy arrays; no torch is imported
(compile, check and emulate run it without loading torch).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import networkx as nx
import numpy as np

from snncc.errors import SnnccError
from snncc.exact_products import ExactProduct
from snncc import spike_products
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LINEAR, LSTM, Conv, Dense, Input, Output, Readout

RECORD_CHOICES = ("outputs", "spikes", "voltage", "all")


@dataclass
class SimulationResult:
    """What a simulation produced. Arrays are (B, T, n) unless stated."""

    outputs: dict[str, np.ndarray]
    spikes: dict[str, np.ndarray] = field(default_factory=dict)
    voltage: dict[str, np.ndarray] = field(default_factory=dict)
    current: dict[str, np.ndarray] = field(default_factory=dict)
    hidden: dict[str, np.ndarray] = field(default_factory=dict)
    readout: np.ndarray | None = None      # (B, n): the score the Readout takes argmax of
    prediction: np.ndarray | None = None   # (B,) int64, ties to the lowest index

    @property
    def output(self) -> np.ndarray:
        """The single Output node's (B, T, n) array."""
        if len(self.outputs) != 1:
            raise SnnccError(f"graph has {len(self.outputs)} outputs; name one", field="outputs")
        return next(iter(self.outputs.values()))


def real_dtype(dtype: object) -> np.dtype:
    """float32 or float64 from a numpy dtype, its name, or a torch dtype (``torch.float32``), without torch."""
    try:
        found = np.dtype(dtype)                        # type: ignore[call-overload]
    except TypeError:
        name = str(dtype).replace("torch.", "")
        found = np.dtype({"float": "float32", "double": "float64"}.get(name, name))
    if found not in (np.float32, np.float64):
        raise SnnccError(f"the reference runs in float32 or float64, not {dtype}", field="dtype")
    return found


def as_input_array(x, dtype: np.dtype) -> np.ndarray:
    """Accept (T, C) or (B, T, C) arrays (numpy, or anything ``np.asarray`` reads); return (B, T, C) of ``dtype``."""
    a = np.asarray(x.detach().cpu().numpy() if hasattr(x, "detach") else x)
    if a.ndim == 2:
        a = a[None]
    if a.ndim != 3:
        raise SnnccError(f"input must have shape (T, C) or (B, T, C), got {tuple(a.shape)}", field="input")
    return a.astype(dtype, copy=False)


def spike_count(v: np.ndarray, theta: np.ndarray, max_spikes: int, fire_test: str) -> np.ndarray:
    """Spikes in one step under a LIF's spike rule: how many times ``v`` passes ``fire_test`` theta while
    theta is subtracted, at most ``max_spikes`` (theta > 0; +inf never fires)."""
    ratio = v / theta
    n = np.floor(ratio) if fire_test == ">=" else np.ceil(ratio) - 1.0
    return np.clip(n, 0.0, float(max_spikes))


def _schedule(g: Graph) -> list[str]:
    zero = nx.DiGraph()
    zero.add_nodes_from(g.nx.nodes)
    zero.add_edges_from((u, v) for u, v, d, _ in g.edges() if d == 0)
    return list(nx.lexicographical_topological_sort(zero, key=list(g.nx.nodes).index))


def _static_nodes(g: Graph) -> set[str]:
    """Nodes whose output depends only on inputs through stateless linear maps."""
    static: set[str] = set()
    for name in nx.topological_sort(g.nx.subgraph([n for n, op in g.items() if isinstance(op, (Input,) + LINEAR)])):
        op = g.node(name)
        if isinstance(op, Input) or all(p in static for p in g.predecessors(name)):
            static.add(name)
    return static


SPARSE_MIN_SIZE = 1 << 16      # Dense weights this large and at most 1/16 nonzero run as sparse products (same
SPARSE_MAX_DENSITY = 1 / 16    # sums, another summation order): below that density scipy's product by the
                               # nonzeros beats BLAS on the whole matrix at every size and batch measured (256 to
                               # 2,048 square, batch 32 and 256: 0.13-0.79x its time), above 1/10 it loses (up to 3.4x)
EXACT_MIN_SIZE = 1 << 16       # float64 weights this large that are integers times a power of two multiply
                               # spikes in float32 (``snncc.exact_products``: the same bits, half the memory read)


def _weight_matrix(op, dtype: np.dtype):
    """The node's weight as the matrix y = x @ W.T uses: dense, scipy CSR where large and sparse (and always
    for a Conv, its connection matrix), an ``ExactProduct`` where large and integer times a power of two, else a
    ``spike_products.FloatProduct`` where large enough for its kernel (spikes summed over the nonzero inputs in C,
    ascending order)."""
    if isinstance(op, Conv):
        from snncc.ir.conv import conv_matrix

        return conv_matrix(op).astype(dtype)
    w = np.asarray(op.weight, dtype=dtype)
    if w.size >= SPARSE_MIN_SIZE and np.count_nonzero(w) <= SPARSE_MAX_DENSITY * w.size:
        import scipy.sparse as sp

        return sp.csr_matrix(w)
    if dtype == np.float64 and w.size >= EXACT_MIN_SIZE:
        product = ExactProduct(w)
        if product.units_t is not None:
            return product
        if w.size >= spike_products.FLOAT_MIN_SIZE:     # smaller: BLAS on every call, no wrapper to ask
            return spike_products.FloatProduct(w)
    return w


def _bias_vector(op, dtype: np.dtype) -> np.ndarray | None:
    if isinstance(op, Conv):
        from snncc.ir.conv import conv_bias_vector

        b = conv_bias_vector(op)
    else:
        b = op.bias
    return None if b is None else np.asarray(b, dtype=dtype)


def _shift(x: np.ndarray, d: int) -> np.ndarray:
    """x[:, t - d] along time, zeros for t < d."""
    if d == 0:
        return x
    out = np.zeros_like(x)
    if d < x.shape[1]:
        out[:, d:] = x[:, :-d]
    return out


def _sigmoid(x: np.ndarray) -> np.ndarray:
    return 0.5 * (1.0 + np.tanh(0.5 * x))


class _Records:
    """(B, T, ...) series filled step by step: the values and dtype ``np.stack`` of the steps would give (a later
    step of a wider dtype widens the record, as stack promotes)."""

    def __init__(self, batch: int, steps: int):
        self.batch, self.steps = batch, steps
        self.series: dict[tuple[str, str], np.ndarray] = {}

    def put(self, key: tuple[str, str], t: int, value: np.ndarray) -> None:
        rec = self.series.get(key)
        if rec is None:
            rec = self.series[key] = np.empty((self.batch, self.steps) + value.shape[1:], value.dtype)
        elif value.dtype != rec.dtype and np.result_type(rec.dtype, value.dtype) != rec.dtype:
            rec = self.series[key] = rec.astype(np.result_type(rec.dtype, value.dtype))
        rec[:, t] = value

    def get(self, key: tuple[str, str], shape: tuple[int, ...], dtype: np.dtype) -> np.ndarray:
        """The filled series, or an empty (B, 0, ...) one when there were no steps."""
        found = self.series.get(key)
        return found if found is not None else np.zeros((self.batch, 0) + shape, dtype)


class _Runner:
    def __init__(self, g: Graph, dtype: np.dtype, record: str, populations=None):
        self.g, self.dtype, self.record = g, dtype, record
        self.populations = None if populations is None else set(populations)
        self.order = _schedule(g)
        self.static = _static_nodes(g)
        self.p: dict[str, tuple] = {}  # parameters as arrays of ``dtype``
        for name, op in g.items():
            if isinstance(op, LINEAR):
                self.p[name] = (_weight_matrix(op, dtype), _bias_vector(op, dtype))
            elif isinstance(op, LIF):
                alpha, beta = op.decays(g.dt)
                self.p[name] = tuple(
                    np.asarray(a, dtype=dtype)
                    for a in (alpha, beta, op.threshold, op.bias if op.bias is not None else np.zeros(op.n))
                )
            elif isinstance(op, LSTM):
                b = np.zeros(op.weight_ih.shape[0])
                for extra in (op.bias_ih, op.bias_hh):
                    if extra is not None:
                        b = b + extra
                self.p[name] = (np.asarray(op.weight_ih, dtype=dtype), np.asarray(op.weight_hh, dtype=dtype),
                                np.asarray(b, dtype=dtype))

    def linear(self, name: str, x: np.ndarray) -> np.ndarray:
        """A Dense or Conv node applied to (..., in) -> (..., out)."""
        w, b = self.p[name]
        if isinstance(w, np.ndarray):
            y = x @ w.T
        elif isinstance(w, (ExactProduct, spike_products.FloatProduct)):   # exact sums, the spike kernel, or BLAS
            y = w.of(x)
        else:                                  # y^T = W x^T, W sparse (a convolution, a folded one)
            flat = x.reshape(-1, x.shape[-1])
            y = np.asarray((w @ flat.T).T).reshape(tuple(x.shape[:-1]) + (w.shape[0],))
        y = y.astype(self.dtype, copy=False)
        return y if b is None else y + b

    def run(self, inputs: dict[str, np.ndarray]) -> SimulationResult:
        g = self.g
        batch, steps = next(iter(inputs.values())).shape[:2]
        full: dict[str, np.ndarray] = {}
        for name in self.order:
            if name not in self.static:
                continue
            op = g.node(name)
            if isinstance(op, Input):
                full[name] = inputs[name]
            else:
                (src,) = g.predecessors(name)
                full[name] = self.linear(name, _shift(full[src], g.delay(src, name)))

        dynamic = [n for n in self.order if n not in self.static]
        # per-step histories of dynamic nodes' outputs: hist[(node, port)][t]
        hist: dict[tuple[str, str], list[np.ndarray]] = {}
        state: dict[str, dict[str, np.ndarray]] = {}
        static_drive: dict[str, np.ndarray] = {}
        for name in dynamic:
            op = g.node(name)
            ports = {g.port(name, s) for s in g.successors(name)} | {"spikes"}
            for port in ports:
                hist[(name, port)] = []
            if isinstance(op, LIF):
                z = np.zeros((batch, op.n), dtype=self.dtype)
                state[name] = {"I": z, "V": z.copy(), "ref": np.zeros((batch, op.n), dtype=np.int32)}
            elif isinstance(op, LSTM):
                z = np.zeros((batch, op.hidden_size), dtype=self.dtype)
                state[name] = {"h": z, "c": z.copy()}
            static_preds = [p for p in g.predecessors(name) if p in self.static]
            if static_preds and isinstance(op, (LIF, Readout, Output, LSTM) + LINEAR):
                static_drive[name] = sum(_shift(full[p], g.delay(p, name)) for p in static_preds)

        want_state = self.record == "all"
        want_voltage = self.record in ("voltage", "all")
        want_spikes = self.record in ("spikes", "voltage", "all")

        # what each dynamic node reads from the others, looked up in the graph once: (source, its history, the
        # edge's delay) in predecessor order (the static ones are in static_drive already)
        feeds = {name: [(src, hist[(src, g.port(src, name))], g.delay(src, name)) for src in g.predecessors(name)
                        if src not in self.static] for name in dynamic}

        def drive(name: str, t: int, width: int) -> np.ndarray:
            total = static_drive[name][:, t] if name in static_drive else None
            for src, series, d in feeds[name]:
                if t - d < 0:
                    continue
                v = series[t - d]
                if v is None:      # released by the window below: a bug, never an absent input
                    raise RuntimeError(f"step {t - d} of '{src}' was released before the edge to '{name}' read it")
                total = v if total is None else total + v
            return total if total is not None else np.zeros((batch, width), dtype=self.dtype)

        # a step's output is kept while an edge may still read it (its longest delay); what the result reports is
        # copied as it comes into one (B, T, n) record per series (``_Records``): no list of T arrays to stack
        window = {(n, p): max([g.delay(n, s) for s in g.successors(n) if g.port(n, s) == p], default=0)
                  for (n, p) in hist}
        reported = {n for n in dynamic if isinstance(g.node(n), (Output, Readout))
                    or (isinstance(g.node(n), LIF) and want_spikes
                        and (self.populations is None or n in self.populations))
                    or (isinstance(g.node(n), LSTM) and want_state)}
        records = _Records(batch, steps)
        ports_of = {n: [p for (m, p) in hist if m == n] for n in dynamic}
        steps_of = [(name, g.node(name)) for name in dynamic]
        for t in range(steps):
            for name, op in steps_of:
                if isinstance(op, LINEAR):
                    out = {"spikes": self.linear(name, drive(name, t, op.in_size))}
                elif isinstance(op, LIF):
                    alpha, beta, theta, bias = self.p[name]
                    st = state[name]
                    i_new = alpha * st["I"] + drive(name, t, op.n)
                    if op.bias is not None and op.bias_placement == "current":
                        i_new = i_new + bias
                    v_new = beta * st["V"] + i_new
                    if op.bias is not None and op.bias_placement == "voltage":
                        v_new = v_new + bias
                    refractory = st["ref"] > 0
                    v_new = np.where(refractory, 0.0, v_new).astype(self.dtype, copy=False)
                    ref = np.where(refractory, st["ref"] - 1, st["ref"])
                    if op.standard_spikes:
                        s = (v_new > theta).astype(self.dtype)
                    else:
                        s = spike_count(v_new, theta, op.max_spikes, op.fire_test).astype(self.dtype, copy=False)
                    fired = s > 0
                    if op.reset == "zero":
                        v_after = np.where(fired, 0.0, v_new).astype(self.dtype, copy=False)
                    elif op.standard_spikes:
                        v_after = np.where(fired, v_new - theta, v_new)  # no 0*inf for integrators
                    else:
                        with np.errstate(invalid="ignore"):     # s = 0 where theta = inf: not taken
                            v_after = np.where(fired, v_new - s * theta, v_new)
                    if op.refractory > 1:
                        ref = np.where(fired, op.refractory - 1, ref).astype(np.int32, copy=False)
                    st["I"], st["V"], st["ref"] = i_new, v_after, ref
                    out = {"spikes": s, "voltage": v_after}
                    if want_state and name in reported:
                        records.put((name, "current"), t, i_new)
                    if want_voltage and name in reported:
                        records.put((name, "voltage"), t, v_after)
                elif isinstance(op, LSTM):
                    w_ih, w_hh, b = self.p[name]
                    st = state[name]
                    x = drive(name, t, op.input_size)
                    gates = x @ w_ih.T + st["h"] @ w_hh.T + b
                    i, f, gg, o = np.split(gates, 4, axis=1)
                    c = _sigmoid(f) * st["c"] + _sigmoid(i) * np.tanh(gg)
                    h = _sigmoid(o) * np.tanh(c)
                    st["h"], st["c"] = h, c
                    out = {"spikes": h}
                else:  # Readout, Output: pass the input through
                    out = {"spikes": drive(name, t, op.size)}
                for port in ports_of[name]:
                    kept = hist[(name, port)]
                    kept.append(out[port])
                    if t - window[(name, port)] - 1 >= 0:      # no edge reads it any more, this step or later
                        kept[t - window[(name, port)] - 1] = None
                if name in reported:
                    records.put((name, "spikes"), t, out["spikes"])

        result = SimulationResult(outputs={})
        for name, op in g.items():
            series = full.get(name)
            if series is None and name in reported:
                series = records.get((name, "spikes"), (op.size,), self.dtype)
            if isinstance(op, Output):
                result.outputs[name] = series
            elif isinstance(op, LIF) and want_spikes and name in reported:
                result.spikes[name] = series
                if want_state:
                    result.current[name] = records.get((name, "current"), (op.n,), self.dtype)
                if want_voltage:
                    result.voltage[name] = records.get((name, "voltage"), (op.n,), self.dtype)
            elif isinstance(op, LSTM) and want_state:
                result.hidden[name] = series
            if isinstance(op, Readout):
                if op.mode == "spike_count":
                    score = series.sum(axis=1)
                elif op.mode == "membrane_max":
                    score = series.max(axis=1)
                else:
                    score = series[:, -1]
                result.readout = score
                result.prediction = np.argmax(score, axis=1).astype(np.int64)
        return result


def simulate(
    g: Graph,
    inputs,
    *,
    dtype: object = np.float64,
    record: str = "outputs",
    populations=None,
) -> SimulationResult:
    """Run the reference semantics of ``g`` on ``inputs``.

    ``inputs``: an array (T, C) / (B, T, C) for a graph with one Input, or a dict by Input name.
    ``dtype``: float64 (default) or float32 (a numpy dtype, its name, or a torch dtype).
    ``record``: "outputs" (outputs and readout only), "spikes" (+ every LIF's spikes), "voltage" (+ LIF post-reset
    voltage) or "all" (+ LIF current, LSTM hidden states). ``populations``: the LIF populations whose records are
    kept (default every one; a (B, T, n) record of a large population costs memory). Every sample starts from
    zero state.
    """
    if record not in RECORD_CHOICES:
        raise SnnccError(f"record must be one of {RECORD_CHOICES}", field="record")
    if populations is not None:
        populations = list(populations)
        unknown = [p for p in populations if p not in g.of_kind(LIF)]
        if unknown:
            raise SnnccError(f"not a LIF population of the graph: {', '.join(map(repr, unknown))}", field="populations")
    real = real_dtype(dtype)
    in_names = g.of_kind(Input)
    if not isinstance(inputs, dict):
        if len(in_names) != 1:
            raise SnnccError(f"graph has {len(in_names)} inputs; pass a dict by name", field="inputs")
        inputs = {in_names[0]: inputs}
    arrays: dict[str, np.ndarray] = {}
    shape = None
    for name in in_names:
        if name not in inputs:
            raise SnnccError("no data given for this input", field=f"input '{name}'")
        x = as_input_array(inputs[name], real)
        width = g.node(name).size
        if x.shape[2] != width:
            raise SnnccError(f"input has {x.shape[2]} channels, the graph expects {width}", field=f"input '{name}'")
        if not np.all(np.isfinite(x)):
            raise SnnccError("input contains NaN or Inf", field=f"input '{name}'")
        if shape is not None and x.shape[:2] != shape:
            raise SnnccError("all inputs must share batch and time sizes", field=f"input '{name}'")
        shape = x.shape[:2]
        arrays[name] = x
    with np.errstate(over="ignore"):       # an unbounded neuron's state may overflow to inf, as torch's did
        return _Runner(g, real, record, populations).run(arrays)
