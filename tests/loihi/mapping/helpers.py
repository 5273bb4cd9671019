"""Small LoihiNetworks built directly (no dependency on the bundle or emulator code)."""

from __future__ import annotations

import numpy as np

from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork


def even_weights(rng, shape, scale=40.0, density=1.0) -> np.ndarray:
    w = (np.round(rng.normal(0.0, scale, size=shape) / 2) * 2).clip(-256, 254).astype(np.int64)
    if density >= 1.0:
        w[w == 0] = 2
    else:
        w[rng.random(shape) >= density] = 0
    return w


def layer(name, n, w, kind="dense", w_rec=None, **kw) -> LoihiLayer:
    params = dict(v_th_mant=100, i_decay=2315, v_decay=327)
    params.update(kw)
    return LoihiLayer(name, kind, n, weight=w, weight_rec=w_rec, **params)


def paper_rsnn(seed=0, delays=(0, 0, 0), scale=40.0) -> LoihiNetwork:
    """The paper's th1 RSNN shape: 48 inputs (24 x 2 copies) -> 450 recurrent -> 28."""
    rng = np.random.default_rng(seed)
    return LoihiNetwork([
        LoihiLayer("input", "input", 48),
        layer("hidden", 450, even_weights(rng, (450, 48), scale), kind="dense_rec",
              w_rec=even_weights(rng, (450, 450), scale / 4), delay=delays[0], delay_rec=delays[1]),
        layer("output", 28, even_weights(rng, (28, 450), scale / 2), delay=delays[2]),
    ], t_sample=270)


def chain(sizes, seed=0, density=1.0, rec=(), **kw) -> LoihiNetwork:
    rng = np.random.default_rng(seed)
    layers = [LoihiLayer("input", "input", sizes[0])]
    for i, n in enumerate(sizes[1:], start=1):
        w = even_weights(rng, (n, sizes[i - 1]), density=density)
        w_rec = even_weights(rng, (n, n), 10.0, density=density) if i in rec else None
        layers.append(layer(f"l{i}", n, w, kind="dense_rec" if i in rec else "dense", w_rec=w_rec, **kw))
    return LoihiNetwork(layers, t_sample=20)


def banded(n, layers, fan_in, seed=0) -> LoihiNetwork:
    """``layers`` sparse layers of ``n`` neurons (scipy CSR); neuron j listens to ``fan_in`` distinct
    sources drawn from a window of 4 * fan_in around position j of the previous layer."""
    import scipy.sparse as sp

    rng = np.random.default_rng(seed)
    out = [LoihiLayer("input", "input", n)]
    for li in range(layers):
        idx = np.arange(fan_in) * 4 + rng.integers(0, 4, size=(n, fan_in)) + (np.arange(n) - 2 * fan_in)[:, None]
        idx = np.sort(idx % n, axis=1)
        w = rng.integers(1, 128, size=n * fan_in) * 2 * np.where(rng.random(n * fan_in) < 0.5, -1, 1)
        weight = sp.csr_matrix((w.astype(np.int16), idx.reshape(-1), np.arange(0, n * fan_in + 1, fan_in)), shape=(n, n))
        out.append(layer(f"s{li}", n, weight, v_th_mant=64 + li % 3, i_decay=1024, v_decay=256))
    return LoihiNetwork(out, t_sample=20)
