"""Voltage biases (NIR v_leak) on populations the timing pass delays (targets/loihi/timing.py).

A compartment bias acts from the chip's first step. NIR graphs have delay-0 projections, so their
populations run s >= 1 steps late on Loihi, and a compartment bias there charged V for s steps before
the population's IR step 0: two_lif_neurons.nir at dt = 1e-3 fired one step early and compile's own
timing check failed. The bias now moves onto the current (exact where alpha = 0) and is carried by an
always-on source; with a synaptic current (alpha != 0) it has no exact form and is refused.
"""

from pathlib import Path

import nir
import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.frontends import LoadOptions, load_model
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense, Input, Output, Readout
from snncc.targets.loihi import lower_model
from snncc.targets.loihi.lowering.timing import lower_timing
from snncc.targets.loihi.emulation.emulator import emulate, lead_steps, pad
from snncc.targets.loihi.checks.exactness import loihi_spikes, validate_lowering
from snncc_test_helpers import run_cli
from snncc.targets.loihi.options import LoihiOptions

TWO_LIF = Path(__file__).resolve().parents[2] / "data" / "nir" / "two_lif_neurons.nir"


@pytest.mark.parametrize("dt", ["1e-4", "1e-3", "1e-2"])
def test_two_lif_neurons_compiles_at_every_dt(dt, tmp_path, capsys):
    out = tmp_path / "x.net"
    code, stdout, err = run_cli(["compile", TWO_LIF, "--dt", dt, "--target", "loihi", "-o", out], capsys)
    assert code == 0 and out.exists(), err
    assert "lif1: its voltage bias is carried on the current" in " ".join(stdout.split()), stdout


def test_the_moved_bias_is_exact_and_the_input_graph_is_untouched():
    g = load_model(TWO_LIF, LoadOptions(dt=1e-3))
    order, rec = lower_timing(g, "exact")
    assert rec.shifts["lif1"] >= 1
    assert order.node("lif1").bias_placement == "current" and g.node("lif1").bias_placement == "voltage"
    low = lower_model(g, LoihiOptions(timing="exact"))
    v = validate_lowering(low.trained, low.order, low.quantized, low.network, low.layers,
                          low.timing_record.shifts, low.timing_record.output_shift, batch=4)
    assert v.timing_exact and v.trained_vs_loihi_order["lif1"] == 1.0
    assert v.trained_vs_loihi_order["lif2"] in (1.0, None)   # None: silent in both on these inputs (nothing to agree on)
    assert low.network.layers[0].always_on == 1          # the input axon that carries lif1's bias
    # no input: V = 1.2 (1 - 0.9^(t+1)) first exceeds 1 at IR step 17 (a compartment bias fired at 16)
    trec = low.timing_record
    x = np.zeros((1, 40, 1), np.uint8)
    emu = loihi_spikes(emulate(low.network, pad(x, lead_steps(trec.shifts, trec.output_shift)), record="all"),
                       low.network, low.layers, trec.shifts, 40)
    assert np.flatnonzero(emu["lif1"][0, :, 0])[0] == 17


def _voltage_biased(delay: int, tau_syn: float) -> Graph:
    """input -delay-> w -> pop (voltage bias) -> readout -> output, dt = 1 ms."""
    g = Graph(1e-3, name="vbias", metadata={"recording_length_s": 0.03})
    g.add("input", Input(width=2))
    g.add("w", Dense(weight=np.array([[0.3, 0.2]])))
    g.add("pop", LIF(n=1, tau_syn=tau_syn, tau_mem=0.01, threshold=1.0, discretisation="euler",
                     bias=np.array([0.12]), bias_placement="voltage"))
    g.add("readout", Readout(width=1))
    g.add("output", Output(width=1))
    g.connect("input", "w", delay=delay)
    g.connect("w", "pop")
    g.connect("pop", "readout")
    g.connect("readout", "output")
    return g


def test_a_voltage_bias_on_time_stays_in_the_compartment():
    g = _voltage_biased(delay=1, tau_syn=2e-3)          # IR delay 1: no shift, the bias acts from step 0 as in the IR
    order, rec = lower_timing(g, "exact")
    assert order is g and rec.shifts == {} and order.node("pop").bias_placement == "voltage"
    low = lower_model(g, LoihiOptions(timing="exact"))
    assert low.network.layers[1].bias is not None and low.network.layers[0].always_on == 0
    v = validate_lowering(low.trained, low.order, low.quantized, low.network, low.layers, {}, 0, batch=3)
    assert v.timing_exact


def test_a_late_voltage_bias_with_a_synaptic_current_is_refused():
    with pytest.raises(SnnccError, match="cannot start on time") as err:
        lower_timing(_voltage_biased(delay=0, tau_syn=2e-3), "exact")
    assert err.value.field == "node 'pop'.bias"


def test_a_cuba_lif_with_v_leak_is_refused_in_one_line(tmp_path, capsys):
    src = tmp_path / "leak.nir"
    nir.write(str(src), nir.NIRGraph(
        nodes={"in": nir.Input(np.array([2])), "w": nir.Linear(weight=np.array([[0.3, 0.2]])),
               "lif": nir.CubaLIF(tau_syn=np.array([2e-3]), tau_mem=np.array([1e-2]), r=np.array([1.0]),
                                  v_leak=np.array([1.2]), v_threshold=np.array([1.0]), w_in=np.array([1.0])),
               "out": nir.Output(np.array([1]))},
        edges=[("in", "w"), ("w", "lif"), ("lif", "out")]))
    out = tmp_path / "x.net"
    code, _, err = run_cli(["compile", src, "--dt", "1e-3", "--target", "loihi", "-o", out], capsys)
    lines = [ln for ln in err.splitlines() if ln.startswith("snncc: error:")]
    assert code == 2 and len(lines) == 1 and "node 'lif'.bias" in lines[0] and "cannot start on time" in lines[0], err
    assert not out.exists()
