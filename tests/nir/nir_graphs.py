"""NIR graphs built the way snnTorch and Norse export them, and independent reference simulations.

snnTorch (export at dt = 1e-4): tau_syn = dt/(1-alpha), tau_mem = dt/(1-beta), r = tau_mem/dt,
w_in = tau_syn/dt, v_leak = 0; RSynaptic's recurrent nn.Linear (with bias) appears either as a
sub-graph {input, lif, w_rec, output} or flat (lif -> w_rec -> lif).
Norse: r = 1, w_in = 1, physical time constants; the time step is not in the file.
"""

from __future__ import annotations

from dataclasses import dataclass

import nir
import numpy as np

SNNTORCH_DT = 1e-4


@dataclass
class SnnTorchLayer:
    """What a snnTorch (R)Synaptic layer holds: per-neuron alpha, beta, threshold."""

    alpha: np.ndarray
    beta: np.ndarray
    threshold: np.ndarray

    def to_nir(self, dt: float = SNNTORCH_DT) -> nir.CubaLIF:
        tau_syn = dt / (1 - self.alpha)
        tau_mem = dt / (1 - self.beta)
        return nir.CubaLIF(tau_syn=tau_syn, tau_mem=tau_mem, r=tau_mem / dt, v_leak=np.zeros_like(self.beta),
                           v_threshold=self.threshold.copy(), w_in=tau_syn / dt)


@dataclass
class BrailleRSNN:
    """A snnTorch-style recurrent network: x -> fc1 -> RSynaptic(hidden) -> fc2 -> Synaptic(out)."""

    w1: np.ndarray
    b1: np.ndarray | None
    w_rec: np.ndarray
    b_rec: np.ndarray | None
    w2: np.ndarray
    b2: np.ndarray | None
    hidden: SnnTorchLayer
    out: SnnTorchLayer

    @classmethod
    def random(cls, rng, n_in=12, n_hidden=38, n_out=7, bias=True, outliers=False, scale=1.0, per_neuron=True,
               rec_std=0.15):
        """Random weights; ``per_neuron`` draws alpha, beta, threshold per neuron, else one value per layer
        (as learned-scalar snnTorch layers export them, and as Loihi's per-layer registers need)."""
        def layer(n):
            size = n if per_neuron else 1
            return SnnTorchLayer(alpha=np.resize(rng.uniform(0.75, 0.95, size), n),
                                 beta=np.resize(rng.uniform(0.85, 0.97, size), n),
                                 threshold=np.resize(rng.uniform(0.8, 1.2, size) if per_neuron else np.ones(1), n))

        w_rec = rng.normal(0, rec_std, (n_hidden, n_hidden)) * scale
        if outliers:  # a few recurrent weights 100x the median magnitude
            idx = rng.choice(w_rec.size, size=max(2, w_rec.size // 200), replace=False)
            w_rec.flat[idx] = np.sign(rng.normal(size=idx.size)) * 100 * np.median(np.abs(w_rec))
        maybe = (lambda n, s: rng.normal(0, s, n)) if bias else (lambda n, s: None)
        return cls(w1=rng.normal(0, 0.8, (n_hidden, n_in)) * scale, b1=maybe(n_hidden, 0.05), w_rec=w_rec,
                   b_rec=maybe(n_hidden, 0.02), w2=rng.normal(0, 0.5, (n_out, n_hidden)) * scale,
                   b2=maybe(n_out, 0.05), hidden=layer(n_hidden), out=layer(n_out))

    def _dense(self, w, b):
        return nir.Linear(weight=w.copy()) if b is None else nir.Affine(weight=w.copy(), bias=b.copy())

    def to_nir(self, form: str = "subgraph", address: str = "dotted") -> nir.NIRGraph:
        """``form`` "subgraph" (RSynaptic as a nested graph) or "flat"; ``address`` how edges name the sub-graph:
        "dotted" ("lif1.input"), "whole" ("lif1"), "keys" (whole, and the sub-graph's keys are "lif1.lif", ...)."""
        n_in, n_h, n_out = self.w1.shape[1], self.w1.shape[0], self.w2.shape[0]
        nodes = {"input": nir.Input(np.array([n_in])), "fc1": self._dense(self.w1, self.b1),
                 "fc2": self._dense(self.w2, self.b2), "lif2": self.out.to_nir(), "output": nir.Output(np.array([n_out]))}
        if form == "flat":
            nodes.update(lif1=self.hidden.to_nir(), w_rec=self._dense(self.w_rec, self.b_rec))
            edges = [("input", "fc1"), ("fc1", "lif1"), ("lif1", "w_rec"), ("w_rec", "lif1"), ("lif1", "fc2"),
                     ("fc2", "lif2"), ("lif2", "output")]
        else:
            # address "keys": the NIR paper's helpers key the sub-graph's own nodes "lif1.lif", ... inside "lif1"
            k = (lambda name: f"lif1.{name}") if address == "keys" else (lambda name: name)
            sub = nir.NIRGraph(
                nodes={k("input"): nir.Input(np.array([n_h])), k("lif"): self.hidden.to_nir(),
                       k("w_rec"): self._dense(self.w_rec, self.b_rec), k("output"): nir.Output(np.array([n_h]))},
                edges=[(k("input"), k("lif")), (k("lif"), k("w_rec")), (k("w_rec"), k("lif")), (k("lif"), k("output"))],
                type_check=False)
            nodes["lif1"] = sub
            into, out_of = ("lif1.input", "lif1.output") if address == "dotted" else ("lif1", "lif1")
            edges = [("input", "fc1"), ("fc1", into), (out_of, "fc2"), ("fc2", "lif2"), ("lif2", "output")]
        return nir.NIRGraph(nodes=nodes, edges=edges, type_check=False)

    def simulate(self, x: np.ndarray, reset: str = "zero") -> tuple[np.ndarray, np.ndarray]:
        """snnTorch's step order, written independently of snncc: for each step
        syn = alpha*syn + input; mem = beta*mem + syn; spk = mem > thr; reset (immediately), or for
        ``zero-delayed`` snnTorch's default Synaptic rule mem = (beta*mem + syn) * (1 - [mem_prev > thr]);
        the recurrent input is W_rec @ spk(t-1) + b_rec (RSynaptic). x: (B, T, n_in) -> spikes."""
        B, T, _ = x.shape
        n_h, n_out = self.w1.shape[0], self.w2.shape[0]

        def lin(w, b, v):
            y = v @ w.T
            return y if b is None else y + b

        def step(layer, syn, mem, drive):
            """One snnTorch Synaptic step: (syn, mem, spikes)."""
            syn = layer.alpha * syn + drive
            if reset == "zero-delayed":  # snnTorch's default: reset from the previous step's membrane
                mem = (layer.beta * mem + syn) * (1 - (mem > layer.threshold))
            else:
                mem = layer.beta * mem + syn
            spk = (mem > layer.threshold).astype(float)
            if reset != "zero-delayed":
                mem = mem * (1 - spk) if reset == "zero" else mem - spk * layer.threshold
            return syn, mem, spk

        syn1, mem1, spk1 = np.zeros((B, n_h)), np.zeros((B, n_h)), np.zeros((B, n_h))
        syn2, mem2 = np.zeros((B, n_out)), np.zeros((B, n_out))
        hs, os = np.zeros((B, T, n_h)), np.zeros((B, T, n_out))
        for t in range(T):
            syn1, mem1, spk1 = step(self.hidden, syn1, mem1,
                                    lin(self.w1, self.b1, x[:, t]) + lin(self.w_rec, self.b_rec, spk1))
            syn2, mem2, spk2 = step(self.out, syn2, mem2, lin(self.w2, self.b2, spk1))
            hs[:, t], os[:, t] = spk1, spk2
        return hs, os


def sparse_inputs(rng, batch=8, steps=120, channels=12, p=0.1) -> np.ndarray:
    return (rng.random((batch, steps, channels)) < p).astype(np.float64)


def norse_graph(rng, n_in=6, n_hidden=10, tau_syn=5e-3, tau_mem=1e-2) -> nir.NIRGraph:
    """Norse-style export: physical time constants, r = 1, w_in = 1; no time step in the file."""
    lif = nir.CubaLIF(tau_syn=np.full(n_hidden, tau_syn), tau_mem=np.full(n_hidden, tau_mem), r=np.ones(n_hidden),
                      v_leak=np.zeros(n_hidden), v_threshold=np.ones(n_hidden), w_in=np.ones(n_hidden))
    return nir.NIRGraph(nodes={"input": nir.Input(np.array([n_in])), "fc": nir.Linear(rng.normal(0, 400.0, (n_hidden, n_in))),
                               "lif": lif, "output": nir.Output(np.array([n_hidden]))},
                        edges=[("input", "fc"), ("fc", "lif"), ("lif", "output")], type_check=False)


def continuous_euler(w: np.ndarray, node: nir.CubaLIF, x: np.ndarray, dt: float) -> np.ndarray:
    """NIR's CubaLIF ODEs stepped by forward Euler (current, then voltage), reset to v_reset."""
    B, T, _ = x.shape
    n = w.shape[0]
    i, v = np.zeros((B, n)), np.zeros((B, n))
    out = np.zeros((B, T, n))
    for t in range(T):
        i = i + dt / node.tau_syn * (-i + node.w_in * (x[:, t] @ w.T))
        v = v + dt / node.tau_mem * ((node.v_leak - v) + node.r * i)
        s = v > node.v_threshold
        v = np.where(s, node.v_reset, v)
        out[:, t] = s
    return out


def run_cli(args: list, capsys) -> tuple[int, str, str]:
    """Run ``snncc args`` in-process; return (exit status, stdout, stderr without its progress lines)."""
    from snncc_test_helpers import run_cli as run

    return run(args, capsys)


# -- a trained graph ---------------------------------------------------------------------------------
def rate_patterns(rng, classes=7, channels=12, active=3, base=0.02, high=0.2) -> np.ndarray:
    """Per class, a firing probability per channel: ``active`` random channels at ``high``, the rest ``base``."""
    p = np.full((classes, channels), base)
    for c in range(classes):
        p[c, rng.choice(channels, size=active, replace=False)] = high
    return p


def pattern_inputs(rng, patterns: np.ndarray, batch: int, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Random sparse spike trains, each drawn from a class's rate pattern: (x (B, T, C) 0/1, labels (B,))."""
    labels = rng.integers(0, patterns.shape[0], batch)
    x = (rng.random((batch, steps, patterns.shape[1])) < patterns[labels][:, None, :]).astype(np.float64)
    return x, labels


def train_snntorch_style(model: BrailleRSNN, rng, patterns: np.ndarray, steps=100, iterations=150, batch=64,
                         lr=5e-3, freeze_outliers=False) -> BrailleRSNN:
    """Train ``model``'s weights and biases in snnTorch's step order (the order of ``simulate``).

    Fast-sigmoid surrogate, reset detached, loss = cross-entropy of the output spike counts; alpha,
    beta and thresholds stay fixed (one per layer, as Loihi needs). ``freeze_outliers`` keeps
    recurrent weights > 20x the median |w| fixed, so the trained graph still has them.
    """
    import torch

    torch.manual_seed(int(rng.integers(1 << 31)))
    names = ("w1", "b1", "w_rec", "b_rec", "w2", "b2")
    params = {k: torch.tensor(getattr(model, k), dtype=torch.float32, requires_grad=True) for k in names}
    med = float(np.median(np.abs(model.w_rec)))
    frozen = torch.tensor(np.abs(model.w_rec) > 20 * med) if freeze_outliers else None
    opt = torch.optim.Adam(params.values(), lr=lr)

    def spike(v):  # Heaviside forward, fast-sigmoid gradient
        sg = v / (1 + 10 * v.abs())
        return (v > 0).float().detach() + sg - sg.detach()

    layer = {k: [torch.tensor(float(getattr(model, k).__dict__[a][0])) for a in ("alpha", "beta", "threshold")]
             for k in ("hidden", "out")}
    for _ in range(iterations):
        x, y = pattern_inputs(rng, patterns, batch, steps)
        x = torch.tensor(x, dtype=torch.float32)
        p = params
        (a1, b1, t1), (a2, b2, t2) = layer["hidden"], layer["out"]
        syn1 = mem1 = spk1 = torch.zeros(batch, p["w1"].shape[0])
        syn2 = mem2 = torch.zeros(batch, p["w2"].shape[0])
        count = 0
        for t in range(steps):
            syn1 = a1 * syn1 + x[:, t] @ p["w1"].T + p["b1"] + spk1 @ p["w_rec"].T + p["b_rec"]
            mem1 = b1 * mem1 + syn1
            spk1 = spike(mem1 - t1)
            mem1 = mem1 * (1 - spk1.detach())
            syn2 = a2 * syn2 + spk1 @ p["w2"].T + p["b2"]
            mem2 = b2 * mem2 + syn2
            spk2 = spike(mem2 - t2)
            mem2 = mem2 * (1 - spk2.detach())
            count = count + spk2
        loss = torch.nn.functional.cross_entropy(count, torch.tensor(y))
        opt.zero_grad()
        loss.backward()
        if frozen is not None:
            p["w_rec"].grad[frozen] = 0
        opt.step()
    for k in names:
        setattr(model, k, params[k].detach().double().numpy())
    return model


def trained_braille_rsnn(seed: int, outliers: bool = False, steps: int = 100, iterations: tuple[int, int] = (150, 100),
                         batch: int = 64) -> tuple[BrailleRSNN, np.ndarray]:
    """A snnTorch-style 12 -> 38 -> 7 graph with biases, trained on 7 rate patterns: (model, patterns).

    ``outliers``: after training, 7 recurrent weights are set to 100x the median |w| and the rest
    fine-tuned around them (frozen), as graphs from other frameworks arrive with outliers that matter.
    """
    import copy

    rng = np.random.default_rng(seed)
    model = BrailleRSNN.random(rng, bias=True, scale=0.3, per_neuron=False, rec_std=0.1)
    patterns = rate_patterns(rng)
    model = train_snntorch_style(model, rng, patterns, steps=steps, iterations=iterations[0], batch=batch)
    if outliers:
        model = copy.deepcopy(model)
        w = model.w_rec
        idx = rng.choice(w.size, size=max(2, w.size // 200), replace=False)
        w.flat[idx] = np.sign(w.flat[idx]) * 100 * np.median(np.abs(w))
        model = train_snntorch_style(model, rng, patterns, steps=steps, iterations=iterations[1], batch=batch,
                                     freeze_outliers=True)
    return model, patterns
