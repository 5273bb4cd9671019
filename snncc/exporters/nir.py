"""snncc IR -> NIR (``snncc export MODEL --to nir``).

Convention (recorded in the NIR graph's metadata and told to the user): NIR is continuous-time,
so each LIF population is written as a CubaLIF (CubaLI if it never spikes) whose forward-Euler
step at the export step ``h`` (default: the IR's dt) reproduces the IR's per-step decays exactly:
    tau_syn = h / (1 - alpha),  tau_mem = h / (1 - beta)      (alpha, beta: the IR's decays)
    r = tau_mem / h,  w_in = tau_syn / h                      (snnTorch's convention: unit gains)
    v_threshold = threshold,  v_reset = 0,  v_leak = b * tau_mem / h for a voltage bias b
For an IR LIF with discretisation "euler" and h == dt the time constants are written unchanged.
Dense -> Affine (bias) or Linear; an edge delay of d steps -> a Delay node of d*h seconds;
the Readout (no NIR node) is left out and the population feeds the Output directly.
What NIR cannot say -- reset by subtraction, refractory periods, the exponential discretisation,
the readout, node order, graph metadata -- is stored as JSON under the graph-metadata key
``snncc``, so ``snncc compile model.nir`` restores the identical IR.
"""

from __future__ import annotations

import io

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from snncc.atomic import write_bytes_atomic
from snncc.errors import SnnccError, one_line
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LSTM, Dense, Input, Output, Readout
from snncc.ir.validate import refuse_spike_rules, validate
from snncc.records import to_jsonable

RECORD_FORMAT = "snncc-nir"
RECORD_VERSION = 1


@dataclass
class ExportReport:
    """What an export wrote and what other frameworks will not honour."""

    output: str
    dt: float
    export_dt: float
    nodes: int
    delay_nodes: int
    convention: str
    not_honoured: list[str] = field(default_factory=list)

    def lines(self) -> list[str]:
        out = [f"wrote {one_line(self.output)} (NIR, {self.nodes} nodes, {self.delay_nodes} Delay nodes)", self.convention]
        if self.not_honoured:
            out.append("other frameworks will NOT honour:")
            out += [f"  - {item}" for item in self.not_honoured]
        out.append("snncc restores the identical IR from this file (metadata key 'snncc').")
        return out


def _euler_tau(decay: np.ndarray, tau: np.ndarray, exact: bool, step: float, name: str, label: str) -> np.ndarray:
    if exact:
        return tau.copy()
    if np.any(decay >= 1.0):
        raise SnnccError("per-step decay is 1.0 (no leak); NIR's CubaLIF needs a finite time constant",
                         field=f"node '{name}'.{label}")
    return step / (1.0 - decay)


def _convention(dt: float, step: float) -> str:
    text = (f"dt convention: NIR has no time step; this graph is written for forward-Euler stepping at "
            f"dt = {step:g} s with r = tau_mem/dt and w_in = tau_syn/dt (snnTorch's convention), so "
            f"1 - dt/tau equals snncc's per-step decays")
    if step != dt:
        text += f" (the model's own dt is {dt:g} s; the step is nominal)"
    return text


def graph_to_nir(graph: Graph, step: float | None = None) -> tuple[Any, ExportReport]:
    """The NIR graph for ``graph`` and a report of the convention and of what NIR loses."""
    import nir

    validate(graph)
    refuse_spike_rules(graph, "NIR")
    graph = _current_bias_on_dense(graph)
    dt = float(graph.dt)
    h = float(dt if step is None else step)
    if not (math.isfinite(h) and h > 0):
        raise SnnccError(f"the export step must be a positive number of seconds, got {h}", field="--nir-dt")
    nodes: dict[str, Any] = {}
    lifs: dict[str, dict[str, Any]] = {}
    readout: dict[str, Any] | None = None
    lost: list[str] = []
    refractory: list[str] = []
    subtract: list[str] = []
    exp: list[str] = []
    for name, op in graph.items():
        if isinstance(op, Input):
            nodes[name] = nir.Input(input_type=np.array([op.width]))
        elif isinstance(op, Output):
            nodes[name] = nir.Output(output_type=np.array([op.width]))
        elif isinstance(op, Dense):
            if op.bias is None:
                nodes[name] = nir.Linear(weight=op.weight.copy())
            else:
                nodes[name] = nir.Affine(weight=op.weight.copy(), bias=op.bias.copy())
        elif isinstance(op, LIF):
            nodes[name] = _cuba(name, op, dt, h)
            lifs[name] = {
                "tau_syn": op.tau_syn.tolist(), "tau_mem": op.tau_mem.tolist(), "threshold": op.threshold.tolist(),
                "reset": op.reset, "refractory": op.refractory, "discretisation": op.discretisation,
                "bias": None if op.bias is None else op.bias.tolist(), "bias_placement": op.bias_placement,
            }
            if op.refractory > 1:
                refractory.append(f"'{name}' {op.refractory}")
            if op.reset == "subtract" and np.any(np.isfinite(op.threshold)):
                subtract.append(f"'{name}'")
            if op.discretisation == "exp":
                exp.append(f"'{name}'")
        elif isinstance(op, Readout):
            preds, succs = graph.predecessors(name), graph.successors(name)
            if len(succs) != 1 or not isinstance(graph.node(succs[0]), Output):
                raise SnnccError("a Readout must feed an Output to be exported to NIR", field=f"node '{name}'")
            readout = {"name": name, "mode": op.mode, "width": op.width, "src": preds[0], "dst": succs[0],
                       "delay_in": graph.delay(preds[0], name), "delay_out": graph.delay(name, succs[0]),
                       "port": graph.port(preds[0], name)}
            lost.append(f"the {op.mode.replace('_', ' ')} readout '{name}' (no NIR node; the population feeds the Output)")
        elif isinstance(op, LSTM):
            raise SnnccError("NIR has no LSTM node; only spiking (CUBA LIF) graphs can be exported", field=f"node '{name}'")
        else:
            raise SnnccError(f"{op.kind} nodes cannot be exported to NIR", field=f"node '{name}'")

    if refractory:
        lost.insert(0, f"refractory periods ({', '.join(refractory)} steps): NIR has none, so importers let V "
                       "integrate right after a spike")
    if subtract:
        lost.insert(0, f"reset by subtraction ({', '.join(subtract)}): NIR's CubaLIF resets to v_reset = 0; "
                       "importers must be told (snncc: --reset subtract)")
    if exp:
        lost.append(f"exponential decays ({', '.join(exp)}): written as Euler-equivalent time constants "
                    "h/(1 - decay), exact for Euler-stepping frameworks at step h (snnTorch); a framework that "
                    "integrates the ODE exactly decays slightly differently")
    edges: list[tuple[str, str]] = []
    delayed: list[str] = []
    for u, v, d, port in graph.edges():
        if readout and v == readout["name"]:
            continue
        if readout and u == readout["name"]:
            u, d, port = readout["src"], readout["delay_in"] + readout["delay_out"], readout["port"]
        src = graph.node(u)
        if isinstance(src, LIF):
            spiking = bool(np.any(np.isfinite(src.threshold)))
            if spiking and port == "voltage":
                raise SnnccError("NIR's CubaLIF sends spikes only; a spiking population's voltage cannot be exported",
                                 field=f"edge {u}->{v}")
            if not spiking and port == "spikes":
                raise SnnccError("a non-spiking population (threshold +inf) sends its voltage in NIR; this edge "
                                 "carries its (always zero) spikes", field=f"edge {u}->{v}")
        if d > 0:
            dname = f"delay_{u}_{v}"
            while dname in nodes or dname in graph:
                dname += "_"
            nodes[dname] = nir.Delay(delay=np.full(src.size, d * h))
            edges += [(u, dname), (dname, v)]
            delayed.append(f"{u}->{v} {d}")
        else:
            edges.append((u, v))
    if delayed:
        lost.append("synaptic delays (" + ", ".join(delayed) + " steps) as Delay nodes: importers without Delay "
                    "support drop them, and a framework that adds its own one-step recurrent delay adds 1 to a loop")

    record = {
        "format": RECORD_FORMAT, "version": RECORD_VERSION, "dt": dt, "export_dt": h, "name": graph.name,
        "metadata": to_jsonable(graph.metadata), "order": list(graph), "lifs": lifs, "readout": readout,
        "edges": [[u, v, d, p] for u, v, d, p in graph.edges()],
    }
    convention = _convention(dt, h)
    metadata = {"snncc": json.dumps(record), "snncc_dt_convention": convention, "dt": h}
    nir_graph = nir.NIRGraph(nodes=nodes, edges=edges, metadata=metadata, type_check=False)
    report = ExportReport(output="", dt=dt, export_dt=h, nodes=len(nodes), delay_nodes=len(delayed),
                          convention=convention, not_honoured=lost)
    return nir_graph, report


def _current_bias_on_dense(graph: Graph) -> Graph:
    """``graph`` with every LIF current bias moved into the bias of a Dense that feeds only that LIF, with delay 0
    (the same term: a Dense bias enters the current at every step from t = 0); NIR has no LIF current bias.
    A LIF without such a Dense keeps its bias (``_cuba`` refuses it)."""
    moved = None
    for name, op in graph.items():
        if not (isinstance(op, LIF) and op.bias is not None and op.bias_placement == "current"):
            continue
        feeds = [p for p in graph.predecessors(name) if isinstance(graph.node(p), Dense) and graph.delay(p, name) == 0
                 and graph.successors(p) == [name]]          # a Dense that feeds only this LIF
        if not feeds:
            continue
        moved = moved or graph.copy()
        dense, lif = moved.node(feeds[0]), moved.node(name)
        dense.bias = lif.bias.copy() if dense.bias is None else dense.bias + lif.bias
        lif.bias = None
    return moved or graph


def _cuba(name: str, op: LIF, dt: float, h: float) -> Any:
    import nir

    alpha, beta = op.decays(dt)
    exact = op.discretisation == "euler" and h == dt
    tau_syn = _euler_tau(alpha, op.tau_syn, exact, h, name, "tau_syn")
    tau_mem = _euler_tau(beta, op.tau_mem, exact, h, name, "tau_mem")
    v_leak = np.zeros(op.n)
    if op.bias is not None:
        if op.bias_placement == "current":
            raise SnnccError("a LIF bias on the current has no NIR equivalent (put it in the incoming Dense's bias)",
                             field=f"node '{name}'.bias")
        v_leak = op.bias * tau_mem / h
    common = dict(tau_syn=tau_syn, tau_mem=tau_mem, r=tau_mem / h, v_leak=v_leak, w_in=tau_syn / h)
    if np.all(np.isinf(op.threshold)):
        return nir.CubaLI(**common)
    if np.any(np.isinf(op.threshold)):
        raise SnnccError("some but not all thresholds are +inf; NIR needs one node type per population",
                         field=f"node '{name}'.threshold")
    return nir.CubaLIF(v_threshold=op.threshold.copy(), v_reset=np.zeros(op.n), **common)


def nir_bytes(graph: Graph, step: float | None = None) -> tuple[bytes, ExportReport]:
    """``graph`` as the bytes of a NIR file, and the report (refusals raised before anything is written)."""
    import nir

    nir_graph, report = graph_to_nir(graph, step=step)
    # Serialised in memory first: HDF5 writing straight to a file crashes the process (SIGSEGV)
    # when the disk fills; a plain write of the finished bytes fails cleanly with ENOSPC instead.
    buf = io.BytesIO()
    nir.write(buf, nir_graph)
    return buf.getvalue(), report


def export_nir(graph: Graph, path: str | Path, step: float | None = None) -> ExportReport:
    """Write ``graph`` as a NIR file atomically; return the report for the user."""
    data, report = nir_bytes(graph, step=step)
    write_bytes_atomic(Path(path), data)
    report.output = str(path)
    return report


def restore_from_record(g: Graph, record: dict[str, Any], dt: float | None = None, reset: str | None = None) -> Graph:
    """The exact IR an snncc export came from: ``g`` is the NIR graph imported at the export step.

    Raises SnnccError if the graph's structure (nodes, edges, delays, ports) no longer matches the
    record, i.e. the file was edited after export.
    """
    readout = record.get("readout")
    out = Graph(float(record["dt"]) if dt is None else dt, name=record.get("name", g.name),
                metadata=json.loads(json.dumps(record.get("metadata") or {})))
    for name in record["order"]:
        if readout and name == readout["name"]:
            out.add(name, Readout(width=int(readout["width"]), mode=readout["mode"]))
            continue
        if name not in g:
            raise SnnccError(f"node '{name}' of the snncc record is missing from the graph", field="metadata.snncc")
        op = g.node(name)
        if name in record["lifs"]:
            spec = record["lifs"][name]
            if not isinstance(op, LIF):
                raise SnnccError(f"node '{name}' is no longer a neuron population", field="metadata.snncc")
            mode, refractory = reset or spec["reset"], spec["refractory"]
            if mode == "zero-delayed":
                mode, refractory = "zero", max(2, refractory)
            op = LIF(n=op.n, tau_syn=spec["tau_syn"], tau_mem=spec["tau_mem"], threshold=spec["threshold"],
                     reset=mode, refractory=refractory, discretisation=spec["discretisation"],
                     bias=spec["bias"], bias_placement=spec["bias_placement"])
        out.add(name, op)
    if set(g) - set(out):
        extra = sorted(set(g) - set(out))[0]
        raise SnnccError(f"node '{extra}' is not in the snncc record", field="metadata.snncc")
    got = {(u, v): (d, p) for u, v, d, p in g.edges()}
    if readout:
        src, dst = readout["src"], readout["dst"]
        d, p = got.pop((src, dst), (None, None))
        if d != readout["delay_in"] + readout["delay_out"]:
            raise SnnccError(f"edge {src}->{dst} does not match the snncc record", field="metadata.snncc")
        got[(src, readout["name"])] = (readout["delay_in"], p)
        got[(readout["name"], dst)] = (readout["delay_out"], "spikes")
    want = {(u, v): (int(d), p) for u, v, d, p in record["edges"]}
    if got != want:
        diff = sorted(set(got.items()) ^ set(want.items()))[0]
        raise SnnccError(f"edge {diff[0][0]}->{diff[0][1]} does not match the snncc record (edited after export?)",
                         field="metadata.snncc")
    for u, v, d, p in record["edges"]:
        out.connect(u, v, delay=int(d), port=p)
    return out
