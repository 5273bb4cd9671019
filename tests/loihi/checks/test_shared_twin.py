"""Lowering runs the float twin once for the scale rule's calibration and the bundle's timing check (one
concatenated batch): the check uses those spikes only for its own inputs and a bundle of the same twin."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

from snncc.frontends import LoadOptions, load_model
from snncc.targets.kit import InternalError
from snncc.targets.loihi import lower_model
from snncc.targets.loihi.checks.exactness import (lead_steps, pad, twin_spikes, twin_structure, validate_lowering,
                                                  validation_spikes)
from snncc.targets.loihi.lowering.lower import VALIDATION_BATCH
from snncc.targets.loihi.options import LoihiOptions

NIR = Path(__file__).resolve().parents[2] / "data" / "nir"


@pytest.fixture(scope="module")
def lowered():
    graph = load_model(NIR / "braille_noDelay_noBias_subtract.nir", LoadOptions(dt=1e-4, reset="subtract"))
    return lower_model(graph, LoihiOptions(allow_reset_change=True))


def _validate(low, order_twin):
    trec = low.timing_record
    return validate_lowering(low.trained, low.order, low.quantized, low.network, low.layers, trec.shifts,
                             trec.output_shift, batch=VALIDATION_BATCH, order_twin=order_twin)


def test_the_shared_run_equals_a_run_of_its_own(lowered):
    inputs, spikes = lowered.validation_float
    trec, steps = lowered.timing_record, int(lowered.network.metadata["steps"])
    assert np.array_equal(inputs, validation_spikes(VALIDATION_BATCH, steps, lowered.network.input_width))
    alone = twin_spikes(lowered.network, lowered.order, lowered.layers,
                        pad(inputs, lead_steps(trec.shifts, trec.output_shift)), trec.shifts, steps)
    assert spikes.keys() == alone.keys() and all(np.array_equal(spikes[k], alone[k]) for k in spikes)
    assert lowered.twin_structure == twin_structure(lowered.network, lowered.order, lowered.layers)
    assert _validate(lowered, lowered.validation_float).timing_exact


def test_given_spikes_are_used_for_the_check_inputs_only(lowered):
    inputs, spikes = lowered.validation_float
    wrong = {k: 1 - v for k, v in spikes.items()}
    with pytest.raises(InternalError, match="timing"):      # used: the check compares them with the IR
        _validate(lowered, (inputs, wrong))
    assert _validate(lowered, (1 - inputs, wrong)).timing_exact   # other inputs: the twin runs again


def test_a_bundle_with_another_twin_does_not_reuse_it():
    """braille_zero_2023's auto rule ('fine') gives its always-on bias source other decay registers than the
    first candidate measured: another float twin, so the timing check runs its own."""
    low = lower_model(load_model(NIR / "braille_zero_2023.nir", LoadOptions(dt=1e-4)), LoihiOptions())
    assert low.validation_float is not None
    assert low.twin_structure != twin_structure(low.network, low.order, low.layers)


def test_the_measured_candidate_is_reused_only_for_its_registers():
    """The scale rule's measurement of a candidate (its flattened kernel and its run on the calibration inputs) serves
    the written bundle only when the registers are the same, compared field by field; taken once."""
    from snncc.targets.loihi.emulation.emulator import PreparedNetwork
    from snncc.targets.loihi.lowering import lower
    from snncc.targets.loihi.network import same_registers

    graph = load_model(NIR / "braille_noDelay_noBias_subtract.nir", LoadOptions(dt=1e-4, reset="subtract"))
    lower._RECENT.clear()                      # measure afresh (lower_model keeps recent results by content)
    lower_model(graph, LoihiOptions(allow_reset_change=True))
    assert not lower._MEASURED                 # a caller other than lower_artefact keeps no measurement
    lower._RECENT.clear()
    low = lower_model(graph, LoihiOptions(allow_reset_change=True), keep_measured=True)
    measured = lower.reuse_measured(low.network)
    assert measured is not None and measured.prepared.network is low.network
    again = PreparedNetwork(low.network).run(measured.xp, record="all")
    for i in again.spikes:
        assert np.array_equal(again.spikes[i], measured.run.spikes[i])
    assert lower.reuse_measured(low.network) is None              # taken once: the list is emptied

    lower._MEASURED.append(lower.MeasuredCandidate(low.network, measured.prepared, measured.xp, measured.run))
    other = copy.deepcopy(low.network)
    other.layers[1].weight = other.layers[1].weight.copy()
    other.layers[1].weight[0, 0] += 2
    assert not same_registers(other, low.network)
    assert lower.reuse_measured(other) is None


def test_a_large_graph_is_lowered_afresh_not_kept(monkeypatch):
    """Above RECENT_MAX_WEIGHTS weights a lowering is not kept (its copy would double the compile's memory): a
    second lowering of the same graph measures again, and nothing is added to the kept results."""
    from snncc.targets.loihi.lowering import lower

    graph = load_model(NIR / "braille_noDelay_noBias_subtract.nir", LoadOptions(dt=1e-4, reset="subtract"))
    lower._RECENT.clear()
    monkeypatch.setattr(lower, "RECENT_MAX_WEIGHTS", 10)
    first = lower_model(graph, LoihiOptions(allow_reset_change=True), keep_measured=True)
    assert not lower._RECENT and lower._MEASURED            # measured, the lowering itself not kept
    lower._MEASURED.clear()
    second = lower_model(graph, LoihiOptions(allow_reset_change=True))
    assert second is not first and not lower._RECENT
    assert np.array_equal(second.network.layers[1].weight, first.network.layers[1].weight)
