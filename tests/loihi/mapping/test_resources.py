import numpy as np
import pytest

from snncc.targets.loihi.mapping.resources import (
    LOIHI1,
    ChipSpec,
    axon_list_bits,
    check_core,
    check_delay,
    delay_bits,
    list_bits,
    min_bits_per_synapse,
)


def test_loihi1_limits_as_published():
    lim = LOIHI1.limits()
    assert (LOIHI1.cores_per_chip, lim["neurons"], lim["input_axons"], lim["output_axons"]) == (128, 1024, 4096, 4096)
    assert lim["synapse_bits"] == 16384 * 64 == 1_048_576
    assert (lim["vth_profiles"], lim["compartment_profiles"], LOIHI1.max_delay) == (8, 32, 62)


def test_chunked_synapse_accounting_matches_the_spec_examples():
    assert int(list_bits(64, 8)) == 576                       # one axon to 64 neurons
    assert 1000 * int(list_bits(1000, 8)) == 9_024_000        # dense 1000 -> 1000
    assert list(list_bits([0, 1, 33, 65], 8)) == [0, 64, 320, 576 + 64]
    assert int(list_bits(64, 8 + delay_bits(62))) == -(-(64 * 14 + 10) // 64) * 64


def test_zero_weights_need_no_synapse_and_sparse_lists_pay_an_index():
    assert int(axon_list_bits(0, 100, 8)) == 0
    assert int(axon_list_bits(100, 100, 8)) == int(list_bits(100, 8))     # full row: dense format
    one = int(axon_list_bits(1, 1000, 8))                                 # 1 synapse in a range of 1000
    assert one == -(-(1 * (8 + 10) + 10) // 64) * 64 == 64
    assert int(axon_list_bits(900, 1000, 8)) == int(list_bits(1000, 8))   # nearly full: dense cheaper


def test_delay_bits():
    assert [delay_bits(d) for d in (0, 1, 2, 3, 62)] == [0, 1, 2, 2, 6]


def test_min_bits_per_synapse_is_a_true_minimum():
    n = np.arange(1, 2000)
    assert np.all(list_bits(n, 8) / n >= min_bits_per_synapse(8) - 1e-12)


def test_design_rules_name_limit_core_and_layer():
    core = {"core": 7, "neurons": 1025, "input_axons": 10, "output_axons": 5000, "synapse_bits": 2_000_000,
            "vth_profiles": 9, "compartment_profiles": 1, "voltage_limits": 1, "layers": [{"layer": "hidden"}]}
    v = check_core(core)
    assert {x.limit for x in v} == {"neurons", "output_axons", "synapse_bits", "vth_profiles"}
    msg = [x.message() for x in v if x.limit == "synapse_bits"][0]
    assert "core 7" in msg and "hidden" in msg and "synapse memory" in msg and "1,048,576" in msg
    d = check_delay("out", 63)
    assert d and "synaptic delay" in d[0].message() and "out" in d[0].message()


def test_chip_spec_round_trip_and_custom_chip():
    small = ChipSpec(name="toy", compartments_per_core=16, synapse_words_per_core=8)
    assert ChipSpec.from_dict(small.to_dict()) == small
    assert small.limits()["synapse_bits"] == 512
    with pytest.raises(Exception):
        small.name = "changed"   # frozen: a chip description is plain, immutable data
