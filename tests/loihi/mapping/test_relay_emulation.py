"""The relayed network is what runs: copy relays reproduce their sources exactly (one step later,
taken back from the projection's delay); rate relays are lossy and only carry the overflow sources."""

import numpy as np
import pytest

from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork
from snncc.targets.loihi.mapping.partition import map_network
from snncc.targets.loihi.mapping.resources import ChipSpec

from .helpers import even_weights, layer

emulator = pytest.importorskip("snncc.targets.loihi.emulation.emulator")
NARROW = ChipSpec(name="narrow", input_axons_per_core=32)


def _net(delay):
    rng = np.random.default_rng(0)
    w = even_weights(rng, (6, 40), 60.0)
    return LoihiNetwork([LoihiLayer("input", "input", 40),
                         layer("wide", 6, w, delay=delay, v_th_mant=60, i_decay=1024, v_decay=512)], t_sample=40)


def test_copy_relays_are_exact_when_overflow_sources_are_silent():
    net = _net(delay=2)
    cm = map_network(net, NARROW)
    rec = cm.transforms[0]
    assert rec["timing_shift_steps"] == 0
    relayed = cm.network
    copied = np.flatnonzero(relayed.layers[1].weight[:rec["copied_exactly"]].any(axis=0))
    x = np.zeros((3, 40, 40), np.uint8)
    rng = np.random.default_rng(1)
    x[:, :, copied] = rng.random((3, 40, copied.size)) < 0.2
    a = emulator.emulate(net, x, record="all")
    b = emulator.emulate(relayed, x, record="all")
    assert a.output_spikes.sum() > 0
    assert np.array_equal(a.output_spikes, b.output_spikes)
    source_of = relayed.layers[1].weight[:rec["copied_exactly"]].argmax(axis=1)   # copy relay r <- its source
    relay_spikes = b.spikes[1][:, :, :rec["copied_exactly"]]
    assert np.array_equal(relay_spikes[:, 1:], x[:, :-1][:, :, source_of])    # each copy = its source, one step later


def test_without_a_delay_to_absorb_the_relay_adds_one_step():
    net = _net(delay=0)
    cm = map_network(net, NARROW)
    assert cm.transforms[0]["timing_shift_steps"] == 1 and "+1 step" in cm.transforms[0]["timing"]
    rec = cm.transforms[0]
    copied = np.flatnonzero(cm.network.layers[1].weight[:rec["copied_exactly"]].any(axis=0))
    x = np.zeros((2, 40, 40), np.uint8)
    x[:, :30, copied] = np.random.default_rng(2).random((2, 30, copied.size)) < 0.2
    a = emulator.emulate(net, x, record="all").output_spikes
    b = emulator.emulate(cm.network, x, record="all").output_spikes
    assert np.array_equal(a[:, :-1], b[:, 1:])          # the same spikes, one step later
