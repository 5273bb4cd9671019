"""Fixtures shared by the Loihi tests: small random networks and an independent chip model."""

from __future__ import annotations

import numpy as np

from snncc.frontends.builders import snn_graph
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork


def even(rng, shape, lo=-256, hi=254):
    return (rng.integers(lo // 2, hi // 2 + 1, size=shape) * 2).astype(np.int16)


def random_network(seed: int, *, recurrent=True, per_synapse_delays=True, bias=True, big=False,
                   split_exponents=False, profiles=False) -> LoihiNetwork:
    """A random 3-layer network; ``big`` uses weight exponents large enough to overflow q and u;
    ``split_exponents`` gives the hidden layer's projections one exponent per synapse (two values);
    ``profiles`` gives the hidden layer a threshold and decays per neuron."""
    rng = np.random.default_rng(seed)
    n_in, n_h, n_out = 7, 11, 5
    wexp = 7 if big else int(rng.integers(-2, 3))
    hidden = LoihiLayer(
        "hidden", "dense_rec" if recurrent else "dense", n_h, weight=even(rng, (n_h, n_in)), wgt_exp=wexp,
        delay=rng.integers(0, 4, (n_h, n_in)) if per_synapse_delays else int(rng.integers(0, 3)),
        v_th_mant=int(rng.integers(50, 2000)) if not big else 2**17 - 1,
        i_decay=int(rng.integers(0, 4097)) if not big else 0, v_decay=int(rng.integers(0, 4097)),
        ref_delay=int(rng.integers(1, 4)),
    )
    if recurrent:
        hidden.weight_rec = even(rng, (n_h, n_h))
        hidden.wgt_exp_rec = int(rng.integers(-3, 3)) if not big else 6
        hidden.delay_rec = rng.integers(0, 3, (n_h, n_h)) if per_synapse_delays else 1
    if profiles:
        hidden.v_th_mant = rng.integers(50, 2000, n_h)
        hidden.i_decay = rng.integers(0, 4097, n_h)
        hidden.v_decay = rng.integers(0, 4097, n_h)
    if split_exponents:
        hidden.wgt_exp = np.where(rng.random((n_h, n_in)) < 0.1, 3, -4)
        if recurrent:
            hidden.wgt_exp_rec = np.where(rng.random((n_h, n_h)) < 0.1, 2, -5)
    if bias:
        hidden.bias = rng.integers(-300, 300, n_h)
        hidden.bias_exp = int(rng.integers(0, 7))
    out = LoihiLayer("out", "dense", n_out, weight=even(rng, (n_out, n_h)), wgt_exp=int(rng.integers(-1, 2)),
                     delay=int(rng.integers(0, 3)), v_th_mant=int(rng.integers(20, 500)),
                     i_decay=int(rng.integers(0, 4097)), v_decay=int(rng.integers(0, 4097)), ref_delay=1)
    return LoihiNetwork([LoihiLayer("input", "input", n_in), hidden, out], t_sample=40)


def chip_model(network: LoihiNetwork, x: np.ndarray):
    """Independent statement of Loihi's arithmetic: one neuron, one synapse, one step at a time.

    Returns spikes[layer] (T, n), u[layer], v[layer] lists of ints, and overflow counts.
    """
    steps = x.shape[0]
    layers = network.layers
    spikes = {0: [[int(b) for b in row] for row in x]}
    us, vs = {}, {}
    counts = {"q_wrap": 0, "u_wrap": 0, "v_clip": 0}

    def to_signed(value, bits):  # two's complement with `bits` magnitude bits + sign
        m = 1 << (bits + 1)
        value %= m
        return value - m if value >= (1 << bits) else value

    def decay(value, reg):
        mag = (abs(value) * (4096 - reg)) // 4096
        return mag if value >= 0 else -mag

    def delay_of(d, j, i):
        return int(d) if np.ndim(d) == 0 else int(d[j][i])

    exponent_of = delay_of   # a scalar, or one per synapse

    def per_neuron(value, j):
        return int(value) if np.ndim(value) == 0 else int(value[j])

    state = {i: {"u": [0] * l.n, "v": [0] * l.n, "r": [0] * l.n} for i, l in enumerate(layers) if i}
    for i in range(1, len(layers)):
        spikes[i], us[i], vs[i] = [], [], []
    for t in range(steps):
        for i in range(1, len(layers)):
            lay, st = layers[i], state[i]
            row_s, row_u, row_v = [], [], []
            for j in range(lay.n):
                q = 0
                for src_layer, w, e, d in ((i - 1, lay.weight, lay.wgt_exp, lay.delay),
                                           (i, lay.weight_rec, lay.wgt_exp_rec, lay.delay_rec)):
                    if w is None:
                        continue
                    for k in range(len(w[j])):
                        ts = t - 1 - delay_of(d, j, k)
                        if ts >= 0 and spikes[src_layer][ts][k]:
                            q += int(w[j][k]) * 2 ** (6 + exponent_of(e, j, k))
                qw = to_signed(q, 21)
                counts["q_wrap"] += qw != q
                u_raw = decay(st["u"][j], per_neuron(lay.i_decay, j)) + qw
                u = to_signed(u_raw, 23)
                counts["u_wrap"] += u != u_raw
                b = 0 if lay.bias is None else int(lay.bias[j]) * 2 ** lay.bias_exp
                v_raw = decay(st["v"][j], per_neuron(lay.v_decay, j)) + u + b
                v = min(max(v_raw, lay.vmin), lay.vmax)
                counts["v_clip"] += v != v_raw
                if st["r"][j] > 0:
                    v = 0
                    st["r"][j] -= 1
                s = int(v > per_neuron(lay.v_th_mant, j) * 64)
                if s:
                    v = 0
                    st["r"][j] = lay.ref_delay - 1
                st["u"][j], st["v"][j] = u, v
                row_s.append(s)
                row_u.append(u)
                row_v.append(v)
            spikes[i].append(row_s)
            us[i].append(row_u)
            vs[i].append(row_v)
    return ({i: np.array(s, np.int64) for i, s in spikes.items()}, {i: np.array(u, np.int64) for i, u in us.items()},
            {i: np.array(v, np.int64) for i, v in vs.items()}, counts)


def small_graph(order="spytorch", seed=0, n_in=8, n_h=20, n_out=5, steps=40, recurrent=True, scale=1.0):
    rng = np.random.default_rng(seed)
    w_in = rng.normal(0, 0.6 * scale, (n_in, n_h))
    w_out = rng.normal(0, 0.5 * scale, (n_h, n_out))
    v_rec = rng.normal(0, 0.15 * scale, (n_h, n_h)) if recurrent else None
    return snn_graph(w_in, w_out, v_rec, dt=0.005, tau_syn=0.006, tau_mem=0.06, threshold=1.0, order=order,
                     metadata={"recording_length_s": steps * 0.005})
