"""Flash and RAM as counted equal what the compilers lay out: sizeof(snn_state_t) on the host and on a Cortex-M4,
the constant arrays' bytes as the ARM object's symbols; the real-time and energy arithmetic of the ESTIMATE."""

from __future__ import annotations

import subprocess

import numpy as np

import pytest

from c_test_graphs import need, network, random_graph, sources


def _sizeof(compiler: list[str], tmp_path, net) -> int:   # noqa: ANN001
    """sizeof(snn_state_t) as the compiler lays it out, read from a symbol's size."""
    for name, data in sources(net).items():
        (tmp_path / name).write_bytes(data)
    (tmp_path / "probe.c").write_text('#include "snn.h"\nsnn_state_t probe_state;\n')
    subprocess.run([*compiler, "-c", "-o", "probe.o", "probe.c"], cwd=tmp_path, check=True, capture_output=True)
    nm = "arm-none-eabi-nm" if "arm" in compiler[0] else "nm"
    out = subprocess.run([nm, "-S", "probe.o"], cwd=tmp_path, check=True, capture_output=True, text=True).stdout
    line = next(ln for ln in out.splitlines() if ln.endswith("probe_state"))
    return int(line.split()[1], 16)


@pytest.mark.parametrize("seed,spikes_per_step", [(1, 1), (2, 3)])
def test_state_bytes_equal_sizeof(tmp_path, seed, spikes_per_step):
    need("gcc", "arm-none-eabi-gcc")
    from snncc.targets.c.artefact.csource import state_bytes

    net = network(random_graph(seed, n_hidden=7, spikes=spikes_per_step), "per-neuron")
    arm = ["arm-none-eabi-gcc", "-mcpu=cortex-m4", "-mthumb", "-fno-common"]
    assert _sizeof(arm, tmp_path, net) == state_bytes(net)
    assert _sizeof(["gcc", "-fno-common"], tmp_path, net) == state_bytes(net)


def test_constant_bytes_equal_the_objects_symbols(tmp_path):
    need("arm-none-eabi-gcc", "arm-none-eabi-nm")
    from snncc.targets.c.estimate.memory import const_bytes

    net = network(random_graph(3, n_hidden=10), "per-neuron-16")
    for name, data in sources(net).items():
        (tmp_path / name).write_bytes(data)
    subprocess.run(["arm-none-eabi-gcc", "-mcpu=cortex-m4", "-mthumb", "-O0", "-c", "-o", "snn.o", "snn.c"],
                   cwd=tmp_path, check=True, capture_output=True)
    out = subprocess.run(["arm-none-eabi-nm", "-S", "snn.o"], cwd=tmp_path, check=True, capture_output=True,
                         text=True).stdout
    rodata = sum(int(ln.split()[1], 16) for ln in out.splitlines() if len(ln.split()) == 4 and ln.split()[2] in "rR")
    counted = const_bytes((tmp_path / "snn.c").read_text())
    assert rodata == counted["weights"] + counted["constants"]


def test_realtime_record_arithmetic():
    from snncc.targets.c.estimate.parts import PARTS
    from snncc.targets.c.estimate.realtime import realtime_record

    part = PARTS["stm32l431rc"]
    r = realtime_record(4000.0, 6000, part, 1e-4, 100)
    assert r["cycles_per_step"] == 4000 * r["cpi_assumed"] and r["cycle_budget_per_step"] == pytest.approx(8000)
    assert r["real_time"] == (r["cycles_per_step"] <= 8000)
    assert r["margin"] == pytest.approx(1 - r["cycles_per_step"] / 8000)
    # energy per step = uA/MHz x V x cycles (pJ), whatever the clock
    assert r["energy_per_step_j"] == pytest.approx(84 * 3.0 * r["cycles_per_step"] * 1e-12)
    assert r["energy_per_sample_j"] == pytest.approx(100 * r["energy_per_step_j"])
    for spec in PARTS.values():
        assert "Rev" in spec["source"] and spec["flash_bytes"] > 0 and spec["ram_bytes"] > 0


def test_hardware_figures_of_a_search_trial():
    from snncc.targets import get_target

    from c_test_graphs import random_graph, spikes

    graph = random_graph(6, n_out=3)
    costs = get_target("c").hardware()
    figures = costs.figures(graph, spikes(8, 20, 5, 0.3, 0), np.arange(8) % 3, {"rule": "per-neuron", "time_steps": 20},
                            estimate_samples=4, emulate_samples=8).as_dict()
    assert figures["fits"] == 1 and figures["flash_bytes"] > 0 and figures["ram_bytes"] > 0
    assert figures["synops_per_step"] > 0 and figures["emulated_on"] == 8
    assert set(costs.front) <= set(costs.objectives)
