"""A layer with more inputs than a core has axons compiles into a relayed bundle: the relays the
mapper plans are in the bundle, the emulator runs them, copy relays are exact, and check measures
what the lossy rate relays cost. Synthetic weights and seeded random spikes."""

import numpy as np
import pytest

from snncc.cli.main import run
from snncc.ir import LIF, Dense, Graph, Input, Output, Readout, save_graph, simulate, validate
from snncc.targets.loihi import lower_model, target
from snncc.targets.loihi.bundle.read import read_bundle
from snncc.targets.loihi.mapping.relays import relay_agreement, relay_network
from snncc.targets.loihi.options import LoihiOptions

N_IN, HIDDEN, OUT, STEPS = 4600, 4, 3, 30


def _wide_graph() -> Graph:
    rng = np.random.default_rng(0)
    g = Graph(dt=1e-3, name="wide")
    g.add("x", Input(width=N_IN))
    w = rng.normal(0, 0.1, (HIDDEN, N_IN))          # small but not rounded to zero: fan-in stays > 4,096
    w[:, :300] += rng.normal(0.5, 0.3, (HIDDEN, 300))        # the important sources: copied exactly
    g.add("w1", Dense(weight=w))
    g.add("h", LIF(n=HIDDEN, tau_syn=5e-3, tau_mem=2e-2, threshold=1.0))
    g.add("w2", Dense(weight=rng.normal(0.8, 0.5, (OUT, HIDDEN))))
    g.add("o", LIF(n=OUT, tau_syn=5e-3, tau_mem=2e-2, threshold=0.5))
    g.add("readout", Readout(width=OUT))
    g.add("y", Output(width=OUT))
    for a, b in [("x", "w1"), ("w1", "h"), ("h", "w2"), ("w2", "o"), ("o", "readout"), ("readout", "y")]:
        g.connect(a, b)
    return validate(g)


@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    d = tmp_path_factory.mktemp("relay")
    save_graph(_wide_graph(), d / "wide.snnir")
    assert run(["compile", str(d / "wide.snnir"), "--target", "loihi", "--time-steps", str(STEPS),
                "-o", str(d / "wide.net")]) == 0
    return d


def test_relayed_bundle_holds_the_mappers_relays(compiled):
    net = read_bundle(compiled / "wide.net")
    names = [lay.name for lay in net.layers]
    assert names == ["x", "h.relay", "h", "o"]
    rec = net.metadata["fan_in_relays"][0]
    assert rec["fan_in"] == N_IN and rec["copied_exactly"] + rec["through_rate_relays"] == N_IN
    assert net.layers[2].fan_in <= 4096 and net.layers[1].n == rec["relay_neurons"]
    # one relay step with no delay to absorb it: tSample and the output shift grow by it
    assert net.t_sample == STEPS + net.metadata["output_shift"] and rec["timing_shift_steps"] == 1
    assert net.core_map["transforms"] and net.core_map["n_cores"] >= 2


def test_copy_relays_are_exact_and_rate_relays_are_measured(compiled):
    plain = lower_model(_wide_graph(), LoihiOptions(time_steps=STEPS)).network
    relayed, plan = relay_network(plain)
    bundle = read_bundle(compiled / "wide.net")
    assert [lay.n for lay in relayed.layers] == [lay.n for lay in bundle.layers]
    assert all(np.array_equal(a.weight, b.weight) for a, b in zip(relayed.layers[1:], bundle.layers[1:]))
    rng = np.random.default_rng(3)
    only_copied = np.zeros((3, STEPS + 5, N_IN), np.uint8)
    copied = np.flatnonzero(relayed.layers[1].weight[:plan.records[0]["copied_exactly"]].any(axis=0))
    only_copied[:, :STEPS, copied] = rng.random((3, STEPS, copied.size)) < 0.1
    exact = relay_agreement(plain, relayed, plan, only_copied)
    assert exact["spikes_equal"] and exact["prediction_agreement"] == 1.0       # exact through copy relays
    everything = (rng.random((3, STEPS + 5, N_IN)) < 0.05).astype(np.uint8)
    lossy = relay_agreement(plain, relayed, plan, everything)                   # rate relays: measured
    assert not lossy["exact_copies_only"] and lossy["timing_shift_steps"] == 1
    assert min(lossy["spike_agreement"].values()) > 0.5


def test_check_reports_what_relays_cost(compiled):
    g = _wide_graph()
    x = (np.random.default_rng(5).random((8, STEPS, N_IN)) < 0.05).astype(np.uint8)
    labels = np.asarray(simulate(g, x).prediction)
    rec = target.check(g, x, labels, {})
    # the measured bundle is the written, relayed one; the same network without relays is beside it
    by_stage = rec.details["accuracy_by_stage"]
    assert [s.key for s in rec.stages][-2:] == ["emulator_without_relays", "emulator"]
    assert by_stage["float_trained"] == 1.0 == rec.accuracy["float"] and by_stage["emulator"] == rec.accuracy["artefact"]
    # every float output saturates and ties here: agreement is undefined (never 0 or 100 %), and so is its loss
    assert rec.argmax_agreement is None and rec.argmax["ties"] == 8 and rec.total_points is None
    assert [s.cause for s in rec.stages][-2:] == ["saturation", "saturation"] and rec.causes["saturation"] is None
    assert any("rate relays" in n for n in rec.notes) and any(n.startswith("relays: (d0) -> (d)") for n in rec.notes)


def test_emulate_cli_runs_the_relayed_bundle(compiled, tmp_path):
    x = (np.random.default_rng(6).random((2, STEPS, N_IN)) < 0.05).astype(np.uint8)
    np.save(tmp_path / "x.npy", x)
    assert run(["emulate", str(compiled / "wide.net"), "--input", str(tmp_path / "x.npy"),
                "-o", str(tmp_path / "r.npz")]) == 0
    got = np.load(tmp_path / "r.npz")
    assert got["output_spikes"].shape == (2, STEPS + 3, OUT)          # the relay step is in the padding
    assert got["output_spikes"].sum() > 0
