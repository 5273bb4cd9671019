"""The weight rules, the state scale, the network file, and ``auto``'s measured choice."""

from __future__ import annotations

import numpy as np
import pytest

from c_test_graphs import NIR_DIR, network, random_graph


@pytest.mark.parametrize("rule", ["per-layer", "per-neuron", "per-layer-16", "per-neuron-16"])
def test_rules_round_to_the_stated_grid(rule):
    from snncc.targets.c.lowering.quantize import float_weights
    from snncc.targets.c.lowering.structure import structure
    from snncc.targets.c.options import RULE_BITS, WEIGHT_LIMIT

    graph = random_graph(2, n_hidden=9)
    st = structure(graph)
    net = network(graph, rule)
    limit = WEIGHT_LIMIT[RULE_BITS[rule]]
    for p in net.populations:
        finite = p.threshold[p.threshold < (1 << 31) - 1]
        assert (1 << 20) <= finite.max() < (1 << 21)
    for q, fq in zip(net.projections, st.projections):
        assert np.abs(q.weights.astype(int)).max() <= limit
        if rule.startswith("per-layer"):
            assert np.all(q.exponent == q.exponent[0])
        # each weight within half a step of the model's, the step being 2**e state units
        step = np.exp2(q.exponent)[:, None] * 2.0 ** -net.populations[q.target].frac_bits
        assert np.all(np.abs(float_weights(net, q) - fq.matrix.toarray()) <= step / 2 + 1e-15)
        # the largest weight of each scale group uses the range (the scale is the smallest that holds it)
        peak = np.abs(q.weights.astype(int)).max(axis=0)
        assert np.all((peak > limit // 2) | (q.exponent == 0) | (peak == 0)) or rule.startswith("per-layer")


def test_network_file_round_trip_and_refusal():
    from snncc.errors import SnnccError
    from snncc.targets.c.lowering.network import network_arrays, network_bytes, read_network

    net = network(random_graph(5, spikes=3), "per-neuron")
    data = network_bytes(net)
    assert network_bytes(read_network(data)) == data            # byte-identical for identical networks
    back = network_arrays(read_network(data))
    for key, value in network_arrays(net).items():
        np.testing.assert_array_equal(back[key], value)
    with pytest.raises(SnnccError) as err:
        read_network(b"not a zip", source="x/network.npz")
    assert err.value.field == "network.npz"


def test_auto_measures_and_chooses_16_bit_only_where_it_agrees_better():
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets.c.lowering.choose import choose
    from snncc.targets.c.lowering.structure import structure

    graph = load_model(NIR_DIR / "braille_zero_2023.nir", LoadOptions(dt=1e-4))
    picked = choose(structure(graph), graph, "auto", 40, 7)
    assert set(picked.candidates) == {"per-layer", "per-neuron", "per-layer-16", "per-neuron-16"}
    assert picked.rule.endswith("-16") and picked.candidates[picked.rule]["vs_default"]["p"] < 0.05
    # a graph whose weights int8 holds exactly keeps the default: nothing is better by the sign test
    exact = random_graph(1, n_hidden=4, biases=False)
    for name, op in exact.items():
        if hasattr(op, "weight"):
            op.weight = np.round(op.weight * 4) / 4
    kept = choose(structure(exact), exact, "auto", 30, 7)
    assert kept.rule == "per-neuron" and "no rule agreed better" in kept.reason


def test_auto_never_chooses_a_rule_that_does_not_fit_the_parts_flash():
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets.c.lowering.choose import choose
    from snncc.targets.c.lowering.structure import structure

    graph = load_model(NIR_DIR / "braille_zero_2023.nir", LoadOptions(dt=1e-4))
    picked = choose(structure(graph), graph, "auto", 40, 7, flash_limit=3000, part="a 3 kB part")
    assert picked.rule == "per-neuron" and "would not fit a 3 kB part's flash" in picked.reason
    assert not picked.candidates["per-neuron-16"]["fits"] and picked.candidates["per-neuron"]["fits"]
