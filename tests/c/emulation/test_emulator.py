"""The emulator is the arithmetic of docs/c.md: checked against a literal one-neuron-at-a-time statement in plain
Python integers (no numpy), on random networks with delays, both resets, refractory periods, multi-spike
events, biases and saturation; stream mode is one continuous run; inputs in the model's own layout."""

from __future__ import annotations

import numpy as np
import pytest

from c_test_graphs import network, random_graph, spikes

INT32_MIN, INT32_MAX = -(1 << 31), (1 << 31) - 1


def literal(net, x):   # noqa: ANN001
    """The arithmetic of snn.c written out neuron by neuron with Python ints: output spikes (B, T, N)."""
    b_n, t_n = x.shape[0], x.shape[1]
    out = np.zeros((b_n, t_n, net.outputs), np.int64)
    for b in range(b_n):
        hist = {-1: [[int(v) for v in x[b, t]] for t in range(t_n)]}
        cur = [[0] * p.n for p in net.populations]
        vol = [[0] * p.n for p in net.populations]
        ref = [[0] * p.n for p in net.populations]
        for i in range(len(net.populations)):
            hist[i] = []
        for t in range(t_n):
            for i, p in enumerate(net.populations):
                s_out = [0] * p.n
                for j in range(p.n):
                    syn = 0
                    for q in net.projections:
                        if q.target != i or t - q.delay < 0:
                            continue
                        src = hist[q.source][t - q.delay]
                        acc = sum(int(c) * int(q.weights[k, j]) for k, c in enumerate(src) if c)
                        syn += acc * (1 << int(q.exponent[j]))
                    x_i = ((int(p.alpha[j]) * cur[i][j] + (1 << 15)) >> 16) + syn
                    x_i += sum(int(term.values[j]) for term in p.bias_i if t >= term.start)
                    i_new = min(max(x_i, INT32_MIN), INT32_MAX)
                    x_v = ((int(p.beta[j]) * vol[i][j] + (1 << 15)) >> 16) + i_new
                    x_v += 0 if p.bias_v is None else int(p.bias_v[j])
                    v = min(max(x_v, INT32_MIN), INT32_MAX)
                    if ref[i][j] > 0:
                        v = 0
                        ref[i][j] -= 1
                    c = 0
                    th = int(p.threshold[j])
                    while p.fires and c < p.max_spikes and (v > th if p.fire_test == ">" else v >= th):
                        v -= th
                        c += 1
                    if c:
                        if p.reset == "zero":
                            v = 0
                        if p.refractory > 1:
                            ref[i][j] = p.refractory - 1
                    cur[i][j], vol[i][j], s_out[j] = i_new, v, c
                hist[i].append(s_out)
                if i == net.output:
                    out[b, t] = s_out
    return out


@pytest.mark.parametrize("seed,big,spikes_per_step,rule", [
    (0, False, 1, "per-neuron"), (1, True, 3, "per-layer"), (2, False, 3, "per-neuron-16"),
    (3, True, 1, "per-layer-16")])
def test_emulator_equals_the_literal_arithmetic(seed, big, spikes_per_step, rule):
    from snncc.targets.c.emulation.emulator import emulate_network

    net = network(random_graph(seed, n_in=4, n_hidden=5, n_out=3, big=big, spikes=spikes_per_step), rule, 16)
    x = spikes(2, 16, 4, 0.4, seed)
    run = emulate_network(net, x)
    np.testing.assert_array_equal(run.output_spikes.astype(np.int64), literal(net, x))
    assert run.counts.sum() > 0
    if big:
        assert sum(run.saturated.values()) > 0


def test_stream_mode_is_one_continuous_run(tmp_path):
    from snncc.targets.c.emulation.emulator import emulate_network
    from snncc.targets.c.emulation.run_artefact import streamed, unstreamed

    net = network(random_graph(7), "per-neuron", 20)
    x = spikes(3, 20, 5, 0.3, 0)
    whole = emulate_network(net, streamed(x, 4)).output_spikes
    assert whole.shape == (1, 3 * 20 + 2 * 4, net.outputs)
    parts = unstreamed(whole, 3, 20, 4)
    np.testing.assert_array_equal(parts[0], emulate_network(net, x[:1]).output_spikes[0])   # the first from rest


def test_inputs_in_the_models_layout_are_tiled_to_its_copies(tmp_path):
    """A model fed two copies of its 3 data channels takes (B, T, 3) data as (B, T, 6) (the authors' RSNN)."""
    from snncc.targets import get_target

    graph = random_graph(8, n_in=6)
    graph.metadata.update({"input_copies": 2, "base_inputs": 3})
    target = get_target("c")
    target.lower(graph, {"rule": "per-neuron", "time_steps": 12}).write(tmp_path / "a")
    x = spikes(2, 12, 3, 0.3, 1)
    run = target.emulate(tmp_path / "a", x)
    np.testing.assert_array_equal(run.arrays()["output_spikes"],
                                  target.emulate(tmp_path / "a", np.tile(x, (1, 1, 2))).arrays()["output_spikes"])
    assert "tiled" in " ".join(run.lines())
