"""Xylo design rules: each refuses in one line naming the rule and the numbers; valid inputs pass."""

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.ir import Dense
from snncc.targets.xylo.lowering import design_rules as rules
from snncc.targets.xylo.chip import AUDIO2, AUDIO3, CHIPS, IMU
from snncc.targets.xylo.lowering.structure import populations

from xylo_models import chain


def small_spec(n=10, n_in=4, n_out=3, syn=2):
    rng = np.random.default_rng(0)
    return dict(weights_in=rng.integers(-5, 5, (n_in, n, syn)).astype(np.int8),
                weights_rec=rng.integers(-5, 5, (n, n, syn)).astype(np.int8),
                weights_out=rng.integers(-5, 5, (n, n_out)).astype(np.int8),
                dash_mem=np.full(n, 2, np.uint8), dash_syn=np.full(n, 2, np.uint8), dash_syn_2=np.full(n, 3, np.uint8),
                dash_mem_out=np.full(n_out, 1, np.uint8), dash_syn_out=np.full(n_out, 1, np.uint8),
                threshold=np.full(n, 100, np.int16), threshold_out=np.full(n_out, 50, np.int16),
                bias=np.zeros(n, np.int16), bias_out=np.zeros(n_out, np.int16),
                weight_shift_in=2, weight_shift_rec=2, weight_shift_out=2, aliases=[[] for _ in range(n)], dt=1e-3)


def test_a_model_that_fits_passes_every_graph_rule():
    g = chain(np.random.default_rng(0))
    for chip in CHIPS.values():
        rules.check_graph(g, populations(g), chip)


@pytest.mark.parametrize("kwargs, chip, text", [
    (dict(n_in=17), AUDIO2, "input channels: the model has 17, Xylo Audio 2 has 16"),
    (dict(n_hidden=1001, rec_scale=0.0), AUDIO2, "hidden neurons: the model needs 1001 (hidden 1001), Xylo Audio 2 has 1000"),
    (dict(n_hidden=497, rec_scale=0.0), IMU, "hidden neurons: the model needs 497 (hidden 497), Xylo IMU has 496"),
    (dict(n_out=9), AUDIO2, "output neurons: the readout population has 9, Xylo Audio 2 has 8"),
    (dict(n_out=33), AUDIO3, "output neurons: the readout population has 33, Xylo Audio 3 has 32"),
    (dict(n_hidden=129, rec_scale=0.0), IMU, "input expansion: the first hidden population 'hidden' has 129 "
                                             "neurons fed by the inputs, Xylo IMU lets inputs reach 128"),
    (dict(n_hidden=65), AUDIO2, "fan-out: neuron 0 of 'hidden' reaches 65 hidden neurons, Xylo Audio 2 allows 64"),
    (dict(delays=(0, 2, 0)), AUDIO2, "delays: a recurrent projection with IR delay 2 steps"),
])
def test_graph_rules_name_the_numbers(kwargs, chip, text):
    g = chain(np.random.default_rng(0), **kwargs)
    with pytest.raises(SnnccError) as err:
        rules.check_graph(g, populations(g), chip)
    assert text in str(err.value) and "\n" not in str(err.value)


def test_output_expansion_and_recurrent_outputs():
    g = chain(np.random.default_rng(0), n_hidden=120, rec_scale=0.0)
    rules.rule_output_expansion(g, populations(g), AUDIO3)        # 120 <= 128 may feed the outputs
    g = chain(np.random.default_rng(0), n_hidden=200, rec_scale=0.0)
    with pytest.raises(SnnccError, match="output expansion: the last hidden population 'hidden' has 200"):
        rules.rule_output_expansion(g, populations(g), AUDIO3)
    g = chain(np.random.default_rng(0))
    g.add("w_out_rec", Dense(np.zeros((3, 3))))
    g.connect("out", "w_out_rec", delay=1)
    g.connect("w_out_rec", "out")
    with pytest.raises(SnnccError, match="output neurons are not recurrent"):
        rules.rule_output_not_recurrent(g, populations(g), AUDIO2)


def test_refractory_period_is_refused():
    g = chain(np.random.default_rng(0))
    g.node("hidden").refractory = 3
    with pytest.raises(SnnccError, match="refractory: 3 steps; Xylo Audio 2's neurons have none"):
        rules.rule_refractory(g, populations(g), AUDIO2)


def test_spec_checks_are_the_spec_records_own():
    rules.check_spec(small_spec(), AUDIO2)
    with pytest.raises(SnnccError, match="values must lie in"):
        rules.check_spec(dict(small_spec(), dash_mem=np.full(10, 16)), AUDIO2)
    with pytest.raises(SnnccError, match="at most 1 synaptic input"):
        rules.check_spec(small_spec(), IMU)
    with pytest.raises(SnnccError, match="fan-out of at most 64"):
        rules.check_spec(small_spec(n=65), AUDIO2)
