import numpy as np
import pytest
import scipy.sparse as sp

from snncc.errors import SnnccError
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork
from snncc.targets.loihi.mapping.partition import map_network
from snncc.targets.loihi.mapping.resources import LOIHI1, ChipSpec

from .helpers import chain, even_weights, layer, paper_rsnn
from .recheck import assert_valid


def test_paper_rsnn_maps_onto_three_cores_the_lower_bound():
    net = paper_rsnn()
    cm = map_network(net)
    d = cm.to_dict()
    assert d["n_cores"] == 3 and d["lower_bound"] == 3 and d["optimal"] and d["n_chips"] == 1
    assert "exact search" in d["lower_bound_method"]
    sizes = sorted((s["layer"], s["stop"] - s["start"]) for c in d["cores"] for s in c["layers"])
    assert sizes == [("hidden", 225), ("hidden", 225), ("output", 28)]
    assert_valid(net, d, LOIHI1)


def test_paper_rsnn_with_exact_timing_delays_still_three_cores():
    net = paper_rsnn(delays=(1, 2, 1))        # delay fields cost synapse bits: hidden needs 3 slices
    cm = map_network(net)
    assert cm.n_cores == 3 and cm.lower_bound == 3
    assert_valid(net, cm.to_dict(), LOIHI1)


def test_mapping_is_deterministic():
    a = map_network(paper_rsnn(seed=3)).to_dict()
    b = map_network(paper_rsnn(seed=3)).to_dict()
    assert a == b


def test_wide_fan_in_5000_to_100_maps_through_relays():
    net = chain([5000, 100], seed=1)
    cm = map_network(net)
    d = cm.to_dict()
    assert len(d["transforms"]) == 1
    t = d["transforms"][0]
    assert t["layer"] == "l1" and t["fan_in"] == 5000
    assert t["copied_exactly"] + t["through_rate_relays"] == 5000 and t["copied_exactly"] > 4000
    assert "lossy" in t["accuracy"] and "+1 step" in t["timing"]
    mapped = cm.network
    assert [lay.name for lay in mapped.layers] == ["input", "l1.relay", "l1"]
    assert max(np.count_nonzero(mapped.layers[2].weight, axis=1)) <= 4096
    assert_valid(mapped, d, LOIHI1)


def test_relay_timing_absorbed_by_an_existing_delay():
    net = chain([4500, 20], seed=2)
    net.layers[1].delay = 3
    cm = map_network(net)
    t = cm.transforms[0]
    assert t["timing_shift_steps"] == 0 and cm.network.layers[2].delay == 2
    assert_valid(cm.network, cm.to_dict(), LOIHI1)


def test_recurrent_population_of_3000_neurons():
    net = chain([100, 3000], seed=4, rec=(1,))
    cm = map_network(net)
    d = cm.to_dict()
    assert d["n_cores"] == d["lower_bound"]          # provably optimal under the accounting
    assert_valid(net, d, LOIHI1)


def test_more_than_128_cores_spans_chips():
    net = chain([1000, 20000], seed=5)
    cm = map_network(net)
    assert cm.n_cores > 128 and cm.n_chips == 2 and cm.lower_bound == cm.n_cores
    chips = {c.chip for c in cm.cores}
    assert chips == {0, 1} and all(c.chip == c.core // 128 for c in cm.cores)
    assert all(c.usage.neurons <= 1024 and c.usage.synapse_bits <= LOIHI1.synapse_bits_per_core for c in cm.cores)


def test_fixed_size_system_refuses_a_map_that_needs_more_chips():
    with pytest.raises(SnnccError, match="cores in the system"):
        map_network(chain([1000, 20000], seed=5), ChipSpec(max_chips=1))


def test_impossible_neuron_names_the_limit_and_the_layer():
    tiny = ChipSpec(name="tiny", synapse_words_per_core=4)        # 256 bits per core
    net = LoihiNetwork([LoihiLayer("input", "input", 10),
                        layer("greedy", 1, np.full((1, 10), 2))], t_sample=5)
    with pytest.raises(SnnccError) as e:
        map_network(net, tiny)
    msg = str(e.value)
    assert "synapse memory" in msg and "greedy" in msg and "no map exists" in msg


def test_recurrent_fan_in_beyond_4096_fails_naming_input_axons():
    n = 4097
    w_rec = sp.csr_matrix(([2] * n, ([0] * n, list(range(n)))), shape=(n, n))
    net = LoihiNetwork([LoihiLayer("input", "input", 2),
                        layer("loop", n, np.full((n, 2), 2), kind="dense_rec", w_rec=w_rec)], t_sample=5)
    with pytest.raises(SnnccError) as e:
        map_network(net)
    assert "input axons" in str(e.value) and "loop" in str(e.value)


def test_delay_beyond_62_fails():
    net = chain([4, 4])
    net.layers[1].delay = 63
    with pytest.raises(SnnccError, match="synaptic delay.*63.*62"):
        map_network(net)


def test_output_axons_force_a_source_split():
    # l1 (1024 neurons) fits one core alone, but each neuron reaches every core of l2 (6 cores)
    net = chain([10, 1024, 600], seed=6)
    cm = map_network(net)
    d = cm.to_dict()
    l1_cores = [c for c in d["cores"] if any(s["layer"] == "l1" for s in c["layers"])]
    assert len(l1_cores) >= 2
    assert max(c["output_axons"] for c in d["cores"]) <= 4096
    assert_valid(net, d, LOIHI1)


def test_threshold_profiles_limit_packing():
    rng = np.random.default_rng(7)
    layers = [LoihiLayer("input", "input", 4)]
    for i in range(10):
        layers.append(layer(f"p{i}", 4, even_weights(rng, (4, 4)), v_th_mant=100 + i))
    net = LoihiNetwork(layers, t_sample=5)
    cm = map_network(net)
    assert cm.n_cores == 2 and max(c.usage.vth_profiles for c in cm.cores) <= 8
    assert_valid(net, cm.to_dict(), LOIHI1)


def test_sparse_weights_count_only_nonzero_synapses():
    n = 900
    net = LoihiNetwork([LoihiLayer("input", "input", n), layer("diag", n, np.diag(np.full(n, 2)))], t_sample=5)
    cm = map_network(net)
    assert cm.n_cores == 1
    c = cm.cores[0]
    assert c.usage.input_axons == n and c.usage.synapse_bits == n * 64
    sparse_net = LoihiNetwork([LoihiLayer("input", "input", n),
                               layer("diag", n, sp.identity(n, dtype=np.int16, format="csr") * 2)], t_sample=5)
    assert map_network(sparse_net).to_dict()["cores"] == cm.to_dict()["cores"]
    assert_valid(net, cm.to_dict(), LOIHI1)


def test_small_layers_share_cores():
    net = chain([20, 30, 30, 10], seed=8)
    cm = map_network(net)
    assert cm.n_cores == 1 and cm.lower_bound == 1
    assert_valid(net, cm.to_dict(), LOIHI1)
