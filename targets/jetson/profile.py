"""``profile`` of a Jetson artefact (``snncc compare``): what the ONNX models hold, and NeuroBench's metrics.

resources   the parameters the step model stores (float32) and the files' sizes; a Jetson's memory is shared
            by the whole board, so no limit is stated
real time   not estimated: latency is measured on the board (``snncc bench`` with TensorRT); None here
energy      None: the paper's Jetson figures are measurements of its own LSTM, not a cost model for this network
NeuroBench  footprint = the step model's initializer bytes (float32 weights and constants as ONNX stores them);
            activations and synaptic operations from the graph run in float32 by the IR reference -- the
            arithmetic the ONNX models compute (their output spikes equal it on the validation inputs at compile;
            ONNX Runtime exposes no hidden population's spikes to read)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np



def initializer_bytes(model_path: Path) -> tuple[int, int]:
    """(bytes, values) of every initializer of the ONNX model at ``model_path``."""
    import onnx
    from onnx import numpy_helper

    model = onnx.load(str(model_path), load_external_data=False)
    arrays = [numpy_helper.to_array(init) for init in model.graph.initializer]
    return int(sum(a.nbytes for a in arrays)), int(sum(a.size for a in arrays))


def profile_artefact(graph, artefact: Path, inputs: np.ndarray, progress=None):
    """The ``Profile`` of the Jetson artefact at ``artefact`` for ``graph`` on ``inputs`` (B, T, C)."""
    from snncc.ir.nodes import LIF, Input
    from snncc.ir.simulate import simulate
    from snncc.targets.jetson.manifest import JETSON_FORMAT
    from snncc.targets.kit.agreement import chunk_size
    from snncc.targets.kit.compute import one_thread
    from snncc.targets.kit.neurobench import Tally, from_tally, graph_projections
    from snncc.targets.kit.profile import Profile, Resource

    manifest = JETSON_FORMAT.open(artefact)
    step = next((v for v in manifest["variants"] if v.get("name") == "step"), None)
    sequence = next(v for v in manifest["variants"] if v.get("name") == "sequence")
    stored, values = initializer_bytes(Path(artefact) / (step or sequence)["file"])
    resources = [Resource("parameters (float32)", values), Resource(f"{(step or sequence)['file']} bytes",
                                                                    (Path(artefact) / (step or sequence)["file"]).stat().st_size, unit="B"),
                 Resource(f"{sequence['file']} bytes", (Path(artefact) / sequence["file"]).stat().st_size, unit="B")]
    lifs = [n for n, op in graph.items() if isinstance(op, LIF)]
    if not lifs:
        return Profile("jetson", resources, None, None, None,
                       ["real time and power are measured on the board (snncc bench, TensorRT); none is estimated here",
                        "no spiking population: NeuroBench 2.3's spiking metrics do not apply (and it counts no "
                        "synaptic operations of LSTM layers)"])
    projections, notes = graph_projections(graph)
    x = np.asarray(inputs)
    name = graph.of_kind(Input)[0]
    tally = Tally(projections, lifs)
    chunk = chunk_size(sum(int(graph.node(p).n) for p in lifs), int(x.shape[1]), 64)
    with one_thread():
        for start in range(0, x.shape[0], chunk):
            part = x[start:start + chunk]
            run = simulate(graph, part, dtype=np.float32, record="spikes")
            tally.add({name: part, **{p: run.spikes[p] for p in lifs}})
            if progress is not None:
                progress(int(part.shape[0]))
    figures = from_tally(tally, stored, f"the initializers of {(step or sequence)['file']} (float32 weights and "
                                        "constants as ONNX stores them)", notes)
    return Profile("jetson", resources, figures, None, None,
                   ["real time and power are measured on the board (snncc bench, TensorRT); none is estimated here",
                    "activations from the graph in float32 (the ONNX models' arithmetic), not read from ONNX Runtime"])
