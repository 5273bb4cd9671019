import numpy as np
import pytest

from snncc.targets.loihi.estimate.energy import PAPER_RSNN, barrier_ns, estimate_energy
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork
from snncc.targets.loihi.mapping.partition import map_network
from snncc.targets.loihi.mapping.resources import ChipSpec

from tests.loihi.mapping.helpers import layer, paper_rsnn


def _two_core_net():
    # input 2 -> a (2 neurons) -> b (2 neurons); a tiny chip puts a and b on different cores/tiles
    w1 = np.array([[2, 0], [2, 2]])
    w2 = np.array([[4, 4], [0, 4]])
    return LoihiNetwork([LoihiLayer("input", "input", 2), layer("a", 2, w1), layer("b", 2, w2)], t_sample=3)


def test_counts_and_costs_by_hand():
    chip = ChipSpec(name="toy", compartments_per_core=2, cores_per_tile=1, mesh_tiles_ew=2, mesh_tiles_ns=2)
    net = _two_core_net()
    cm = map_network(net, chip)
    assert cm.n_cores == 2 and [s.layer for s in cm.cores[0].layers] == ["a"]
    spikes = {0: np.array([[[1, 0], [0, 1], [0, 0]]], np.uint8),      # (B=1, T=3, n)
              1: np.array([[[0, 0], [1, 1], [0, 0]]], np.uint8),
              2: np.array([[[0, 0], [0, 0], [1, 0]]], np.uint8)}
    u = {1: np.array([[[2, 2], [0, 0], [0, 0]]]), 2: np.array([[[0, 0], [4, 4], [4, 0]]])}
    v = {1: np.zeros((1, 3, 2), np.int64), 2: np.zeros((1, 3, 2), np.int64)}
    est = estimate_energy(net, cm, spikes, u, v, input_note="hand-made")
    c = est.counts
    # synops: input 0 -> a0, a1 (2); input 1 -> a1 (1); a0 -> b0 (1); a1 -> b0, b1 (2); b has no targets
    assert c["synaptic_ops"] == 2 + 1 + 1 + 2
    # active: a: t0 both (u changed), t1 both (spiked / u changed), t2 none; b: t1 both, t2 b0 (spike) + b1 (u changed)
    assert c["active_updates"] == 2 + 2 + 2 + 2 and c["inactive_updates"] == 12 - 8
    # messages: inputs are injected at tile (0,0) = core 0's tile: 2 messages in tile; a -> core 1 (one tile east)
    assert c["messages_in_tile"] == 2 and c["hops_east_west"] == 2 and c["hops_north_south"] == 0
    e = chip.energy
    expected_pj = 6 * e.synop_pj + 8 * e.update_active_pj + 4 * e.update_inactive_pj + 2 * e.spike_in_tile_pj + 2 * e.hop_ew_pj
    assert est.energy_uj["total"] == pytest.approx(expected_pj * 1e-6)
    assert est.step_ns["barrier"] == pytest.approx(barrier_ns(2, e))
    assert est.delay_ms > 0 and "ESTIMATE" in est.label


def test_barrier_interpolates_the_table():
    e = ChipSpec().energy
    assert barrier_ns(1, e) == 113 and barrier_ns(32, e) == pytest.approx(465)


def test_paper_rsnn_estimate_is_labelled_and_beside_the_paper():
    pytest.importorskip("snncc.targets.loihi.emulation.emulator")
    from snncc.targets.loihi.estimate.energy import emulate_and_estimate

    net = paper_rsnn(scale=20.0)
    cm = map_network(net)
    x = (np.random.default_rng(0).random((2, 270, 48)) < 0.05).astype(np.uint8)
    est = emulate_and_estimate(cm.network, cm, x, "random sparse inputs", batch_size=1)
    d = est.to_dict()
    assert d["label"].startswith("ESTIMATE") and d["paper_measurement"] == PAPER_RSNN
    assert d["samples"] == 2 and d["n_cores"] == 3
    assert d["counts_per_sample"]["input_spikes"] == pytest.approx(x.sum() / 2)
    assert d["energy_uj_per_sample"]["total"] > 0 and d["delay_ms_per_sample"] > 0
