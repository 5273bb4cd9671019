"""--replicas K (targets/loihi/lowering/replicate.py): K relays per input channel and K copies of every
hidden neuron, each weight split over K synapses. Exact in float, exact on the chip against its own IR,
read back by check as the model, refused in one line where it does not apply, and K times finer once the
per-neuron scales of fine-tuning's start use it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from snncc.measure.agreement import argmax_agreement
from snncc.finetune.teacher import run_teacher
from snncc.frontends import LoadOptions, load_model
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense, Input, Output, Readout
from snncc.ir.simulate import simulate
from snncc_test_helpers import run_cli
from snncc.targets.loihi.checks.exactness import random_spikes
from snncc.targets.loihi.lowering.replicate import model_sizes, replicate
from snncc.targets.loihi.options import LoihiOptions

NIR = Path(__file__).resolve().parents[2] / "data" / "nir"
ZERO = NIR / "braille_zero_2023.nir"


def _biased_chain(late: int = 0) -> Graph:
    """12 -> 9 (recurrent, Dense and LIF current biases, a delayed input edge; ``late``: the delay of the edge
    fc1 -> h) -> 5 (voltage bias)."""
    rng = np.random.default_rng(3)
    g = Graph(dt=1e-3)
    g.add("in", Input(12))
    g.add("fc1", Dense(rng.normal(0, 0.6, (9, 12)), bias=rng.normal(0, 0.1, 9)))
    g.add("rec", Dense(rng.normal(0, 0.3, (9, 9)), bias=rng.normal(0, 0.05, 9)))
    g.add("h", LIF(9, tau_syn=5e-3, tau_mem=1e-2, threshold=1.0, bias=rng.normal(0, 0.05, 9)))
    g.add("fc2", Dense(rng.normal(0, 0.8, (5, 9)), bias=rng.normal(0, 0.05, 5)))
    g.add("o", LIF(5, tau_syn=5e-3, tau_mem=2e-2, threshold=1.0, bias=np.full(5, 0.02), bias_placement="voltage"))
    g.add("read", Readout(5))
    g.add("out", Output(5))
    for a, b, d in (("in", "fc1", 2), ("fc1", "h", late), ("h", "rec", 1), ("rec", "h", 0), ("h", "fc2", 0),
                    ("fc2", "o", 0), ("o", "read", 0), ("read", "out", 0)):
        g.connect(a, b, d)
    return g


def _dyadic(graph: Graph) -> Graph:
    """``graph`` with every weight and bias a multiple of 2^-12: then every sum the float reference forms is exact
    whatever its order, and so is each of K = 2^k synapses of W/K. (The split is exact in real arithmetic for any K;
    in float, the replicated graph sums the same numbers in another order, so for other weights both graphs are
    right up to rounding and a neuron at its threshold may fire in one and not the other.)"""
    out = graph.copy()
    for _, op in out.items():
        for name in ("weight", "bias"):
            value = getattr(op, name, None)
            if isinstance(value, np.ndarray):
                setattr(op, name, np.round(value * 4096.0) / 4096.0)
    return out


@pytest.mark.parametrize("copies", [2, 4])
@pytest.mark.parametrize("which", ["zero", "chain", "late chain", "subtract"])
def test_replicated_graph_spikes_equal_the_model(which, copies):
    if which.endswith("chain"):
        graph = _biased_chain(late=1 if which == "late chain" else 0)
    else:
        path = ZERO if which == "zero" else NIR / "braille_noDelay_noBias_subtract.nir"
        graph = load_model(path, LoadOptions(dt=1e-4, reset=None if which == "zero" else "subtract"))
    graph = _dyadic(graph)
    rep, record = replicate(graph, copies)
    x = random_spikes(8, 96, 12, 0.1, seed=1)
    pops = [name for name, op in graph.items() if isinstance(op, LIF)]
    a = simulate(graph, x, record="spikes").spikes
    b = simulate(rep, x, record="spikes").spikes
    assert record["replicas"] == copies and record["relay"] in rep and record["relay"] not in graph
    late = 2 if which.endswith("chain") else 0     # the input edge's delay is kept before the relays
    seen = np.zeros_like(x)
    seen[:, late:] = x[:, :x.shape[1] - late]
    assert np.array_equal(b[record["relay"]][..., :12 * copies], np.tile(seen, (1, 1, copies)))
    for name in pops:
        n = graph.node(name).n
        assert model_sizes(record)[name] == n
        ref = a[name]
        assert ref[..., :n].any()                       # never a silent comparison
        got = b[name]
        k = got.shape[-1] // n
        assert k == (1 if name == pops[-1] else copies)
        for c in range(k):                               # every copy fires as the model's neuron
            assert np.array_equal(got[..., c * n:(c + 1) * n], ref)


def test_replicas_one_is_the_model_itself():
    graph = _biased_chain()
    assert replicate(graph, 1) == (graph, None)


def test_compile_replicated_is_exact_and_as_portable_as_the_plain_bundle():
    from snncc.targets.loihi.bundle.portability import netx_runnable
    from snncc.targets.loihi.lowering.lower import lower_artefact

    graph = load_model(ZERO, LoadOptions(dt=1e-4))
    plain = lower_artefact(graph, LoihiOptions(scale="per-layer", time_steps=64))
    rep = lower_artefact(graph, LoihiOptions(scale="per-layer", time_steps=64, replicas=2))
    v = rep.validation
    assert v["timing_exact"] and v["quantized_params_exact"] and v["kernel_exact"]
    assert [lay.n for lay in rep.network.layers[1:3]] == [12 * 2 + 2, 38 * 2 + 1]   # relays + 2 always-on; copies + source
    assert rep.network.metadata["replication"]["replicas"] == 2
    assert rep.network.metadata["compile_options"]["replicas"] == 2
    assert ({g.feature for g in netx_runnable(rep.network)} == {g.feature for g in netx_runnable(plain.network)})
    assert rep.network.t_sample == plain.network.t_sample + 1       # the relay's step of latency


@pytest.mark.parametrize("late", [0, 1])
def test_compile_replicated_chains_exactly(late):
    """Biases on the first population's Dense, recurrent Dense and LIF current; the Dense -> LIF edge with and
    without a delay (then the biases stay on the population, not on the always-on relays)."""
    from snncc.targets.loihi.lowering.lower import lower_artefact

    graph = _biased_chain(late)
    graph.node("o").bias = None          # (a voltage bias on a shifted population has no exact Loihi form)
    art = lower_artefact(graph, LoihiOptions(scale="per-layer", time_steps=64, replicas=2))
    v = art.validation
    assert v["timing_exact"] and v["quantized_params_exact"] and v["kernel_exact"]
    assert art.network.metadata["replication"]["always_on_relays"] == (2 if late == 0 else 0)


def test_check_reads_a_replicated_bundle_as_the_model(tmp_path, capsys):
    out = tmp_path / "r.net"
    code, stdout, err = run_cli(["compile", str(ZERO), "--dt", "1e-4", "--scale", "per-layer", "--replicas", "2",
                                 "--time-steps", "64", "-o", str(out), "--json"], capsys)
    assert code == 0, err
    from snncc.targets.loihi.checks.written import open_bundle

    graph = load_model(ZERO, LoadOptions(dt=1e-4))
    bundle = open_bundle(out, graph)
    assert bundle.populations == ["lif1.lif", "lif2"]
    assert bundle.lowered is not None and bundle.stages_note is None      # re-derived: the breakdown is given
    spikes, _ = bundle.run(random_spikes(4, 64, 12, 0.08, seed=2))
    assert spikes["lif1.lif"].shape == (4, 64, 38) and spikes["lif2"].shape == (4, 64, 7)
    code, stdout, err = run_cli(["check", str(ZERO), "--dt", "1e-4", "--artefact", str(out), "--samples", "40",
                                 "--json"], capsys)
    assert code == 0, err
    rec = json.loads(stdout)
    assert [s["cause"] for s in rec["stages"]][-3:] == ["weights", "decays", "saturation"]   # the breakdown by cause
    assert None not in {rec["causes"][c] for c in ("weights", "decays", "saturation", "timing")}
    assert set(rec["details"]["layer_spike_agreement"]) == {"lif1.lif", "lif2"}          # the model's populations
    data = tmp_path / "labelled.npz"                                          # the accuracy path too
    np.savez(data, inputs=random_spikes(12, 64, 12, 0.08, seed=3), labels=np.arange(12) % 7)
    code, stdout, err = run_cli(["check", str(ZERO), "--dt", "1e-4", "--artefact", str(out), "--data", str(data),
                                 "--json"], capsys)
    assert code == 0, err
    labelled = json.loads(stdout)
    assert labelled["causes"]["weights"] is not None and "ir_quantized" in labelled["details"]["accuracy_by_stage"]


@pytest.mark.parametrize("value", ["0", "17", "two"])
def test_bad_replicas_are_refused_in_one_line(tmp_path, capsys, value):
    out = tmp_path / "r.net"
    code, _, err = run_cli(["compile", str(ZERO), "--dt", "1e-4", "--replicas", value, "-o", str(out)], capsys)
    assert code == 2
    lines = [ln for ln in err.strip().splitlines() if ln.startswith("snncc: error")]
    assert len(lines) == 1 and "--replicas" in lines[0] and "Traceback" not in err
    assert not out.exists()


def test_replicas_refused_for_a_bundle_in_map(tmp_path, capsys):
    out = tmp_path / "p.net"
    code, _, err = run_cli(["compile", str(ZERO), "--dt", "1e-4", "--time-steps", "32", "-o", str(out)], capsys)
    assert code == 0, err
    code, _, err = run_cli(["map", str(out), "--replicas", "2"], capsys)
    assert code == 2 and "--replicas" in err and "does not apply to a written artefact" in err


def test_replicas_make_the_per_neuron_start_agree_better():
    """The point of it: fine-tuning's per-neuron start (rescale.py) on braille_zero, 4 copies against none,
    on the same seeded held-out inputs (measured by bench/studies/finetune_goals.py at full size: 0.90 -> 0.94)."""
    from snncc.finetune.inputs import split_inputs
    from snncc.targets.loihi.finetune.run import network_counts
    from snncc.targets.loihi.lowering.lower import lower_model
    from snncc.targets.loihi.finetune.rescale import rescaled

    graph = load_model(ZERO, LoadOptions(dt=1e-4))
    split = split_inputs(width=12, steps=128, density=0.08, train=128, validation=1, held_out=300, seed=0)
    held, cal = split.x[split.held_out], split.x[split.train]
    teacher = run_teacher(graph, held, ("lif1.lif", "lif2"), voltage=False).counts
    figures = {}
    for k in (1, 4):
        low = lower_model(graph, LoihiOptions(scale="per-layer", replicas=k), t_sample=128)
        names = tuple(c.lif for c in low.layers)
        net = rescaled(low, low.network, cal, run_teacher(low.trained, cal, names, voltage=False).spikes)
        figures[k] = argmax_agreement(teacher, network_counts(low, 128, net, held)).share
    assert figures[4] > figures[1] + 0.02, figures


def test_finetune_with_replicas_writes_the_bundle_and_the_adapted_graph(tmp_path, capsys):
    """--finetune on a replicated network: its start uses the copies, the adapted graph (relays and copies,
    the relays' current bias moved into their Dense for NIR) loads back, and check measures the bundle."""
    out, adapted = tmp_path / "t.net", tmp_path / "adapted.nir"
    code, stdout, err = run_cli(["compile", str(ZERO), "--dt", "1e-4", "--scale", "per-layer", "--replicas", "2",
                                 "--time-steps", "32", "-o", str(out), "--finetune", "--finetune-samples", "32",
                                 "--finetune-epochs", "1", "--finetune-out", str(adapted), "--json"], capsys)
    assert code == 0, err
    record = json.dumps(json.loads(stdout))
    assert "per-neuron scales" in record and out.is_file() and adapted.is_file()
    back = load_model(adapted)
    assert any(op.n == 38 * 2 for _, op in back.items() if isinstance(op, LIF))
    code, stdout, err = run_cli(["check", str(ZERO), "--dt", "1e-4", "--artefact", str(out), "--samples", "20",
                                 "--json"], capsys)
    assert code == 0, err
    assert set(json.loads(stdout)["details"]["layer_spike_agreement"]) == {"lif1.lif", "lif2"}


def test_replicas_refused_for_a_single_population(tmp_path, capsys):
    out = tmp_path / "one.net"
    code, _, err = run_cli(["compile", str(NIR / "lif_norse.nir"), "--dt", "1e-4", "--replicas", "2", "-o", str(out)],
                           capsys)
    lines = [ln for ln in err.strip().splitlines() if ln.startswith("snncc: error")]
    assert code == 2 and len(lines) == 1 and "--replicas" in lines[0] and "feeds another" in lines[0], err
    assert not out.exists()


def test_an_adapted_graph_nir_refuses_leaves_no_bundle(tmp_path, capsys, monkeypatch):
    """compile --finetune --finetune-out builds the adapted NIR before writing anything: when NIR refuses it,
    one line, exit 2, and neither the bundle nor the NIR file exists."""
    import snncc.exporters.nir as nir_export
    from snncc.errors import SnnccError

    def refuse(graph, step=None):
        raise SnnccError("a LIF bias on the current has no NIR equivalent", field="node 'x'.bias")

    monkeypatch.setattr(nir_export, "nir_bytes", refuse)
    out, adapted = tmp_path / "t.net", tmp_path / "adapted.nir"
    code, _, err = run_cli(["compile", str(ZERO), "--dt", "1e-4", "--scale", "per-layer", "--time-steps", "32", "-o",
                            str(out), "--finetune", "--finetune-samples", "16", "--finetune-epochs", "1",
                            "--finetune-out", str(adapted)], capsys)
    lines = [ln for ln in err.strip().splitlines() if ln.startswith("snncc: error")]
    assert code == 2 and len(lines) == 1 and "no NIR equivalent" in lines[0], err
    assert not out.exists() and not adapted.exists()


def test_the_library_refuses_zero_replicas():
    """``replicas=0`` given to the library (not through the CLI's check) is refused, not read as 1."""
    from snncc.errors import SnnccError
    from snncc.targets.loihi.lowering.lower import lower_model

    with pytest.raises(SnnccError, match="replicas must be a whole number from 1 to 16") as err:
        lower_model(load_model(ZERO, LoadOptions(dt=1e-4)), LoihiOptions(scale="per-layer", replicas=0))
    assert err.value.field == "--replicas"
