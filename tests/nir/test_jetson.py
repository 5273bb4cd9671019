"""NIR graphs on the Jetson target: the ONNX artefact against an independent snnTorch-order simulation.

Synthetic: random snnTorch-style weights (biases, per-neuron alpha/beta/threshold) and random
sparse spikes. ONNX Runtime on this CPU stands in for TensorRT on the board.
"""

import nir
import numpy as np
import onnxruntime as ort

from nir_graphs import BrailleRSNN, run_cli, sparse_inputs

STEPS = 30


def test_biased_per_neuron_nir_graph_runs_in_onnx_exactly_as_snntorch_would(tmp_path, capsys):
    rng = np.random.default_rng(11)
    model = BrailleRSNN.random(rng, bias=True, scale=0.5, per_neuron=True, rec_std=0.3)
    src = tmp_path / "g.nir"
    nir.write(str(src), model.to_nir())
    out = tmp_path / "jet"
    code, _, err = run_cli(["compile", src, "--target", "jetson", "-o", out, "--time-steps", STEPS], capsys)
    assert code == 0, err
    x = sparse_inputs(rng, batch=16, steps=STEPS, p=0.1)
    session = ort.InferenceSession(str(out / "model.onnx"), providers=["CPUExecutionProvider"])
    counts, spikes = session.run(["counts", "output_spikes"], {"events": x.astype(np.float32)})
    _, expected = model.simulate(x)              # snnTorch's step order, written independently of snncc
    assert expected.sum() > 0
    np.testing.assert_array_equal(spikes, expected.astype(np.float32))
    np.testing.assert_array_equal(counts, expected.sum(axis=1).astype(np.float32))
