"""Loihi 1's integer arithmetic as a differentiable torch model (for deployment fine-tuning).

The forward pass is the emulator's rule (``emulation/emulator.py``, docs/loihi.md) computed exactly
in float64 tensors that hold integers, per compartment and chip step t:

    q  = wrap21( sum_d  W_d s_pre[t-1-d]  +  sum_d  R_d s_self[t-1-d] )     W = 2*round(P) * 2**(6+wgtExp)
    u  = wrap23( trunc(u * (4096 - round(iDecay)) / 4096) + q )
    v  = clip( trunc(v * (4096 - round(vDecay)) / 4096) + u + bias * 2**biasExp, vmin, vmax )
    v  = 0 while refractory ;  s = v > round(vThMant) * 2**6 ;  v = 0 where s, refractory refDelay - 1

so on the integer registers it exports it produces the emulator's spikes, u and v bit for bit
(tested). The learnable parameters are float shadows that round to the registers: half weight
mantissas P (the weight is the even integer 2*round(P), |P| <= 128), one threshold mantissa and one
iDecay / vDecay register per compartment profile (neurons that share a register value keep sharing
it, so the number of profiles never grows), and voltage-bias mantissas where the model has them.
Weight exponents, delays, refDelay and the always-on bias sources stay as lowered (the scale rule's
format is kept: a per-layer bundle stays per-layer). The rounding, truncation and wraps pass
gradients straight through; spikes use the fast-sigmoid surrogate of ``snncc.finetune.ste``.

A current-bias term carried by ``refDelay`` always-on sources (``bias_sources.py``) is one shared
column of parameters, repeated over its sources, so it stays one bias. The sources themselves fire
on every free step whatever the registers are (their bias exceeds their threshold, no synapse
reaches them); ``export`` re-derives their bias from the new threshold so that this stays true.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np
import torch

from snncc.targets.kit import SnnccError
from snncc.targets.kit.finetuning import StudentRun
from snncc.targets.kit.finetuning import round_ste, spike, trunc_ste, wrap_ste
from snncc.targets.loihi import chip
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork

HALF_MIN, HALF_MAX = chip.WEIGHT_MIN // 2, chip.WEIGHT_MAX // 2     # half mantissas: -128 .. 127


@dataclass
class ChipRun:
    """A run in chip time: per layer (1..L) spikes, current u, post-reset voltage v and pre-reset
    voltage, each (B, T_chip, n) over all compartments (always-on sources included)."""

    spikes: dict[int, torch.Tensor] = field(default_factory=dict)
    current: dict[int, torch.Tensor] = field(default_factory=dict)
    voltage: dict[int, torch.Tensor] = field(default_factory=dict)
    voltage_pre: dict[int, torch.Tensor] = field(default_factory=dict)
    threshold: dict[int, torch.Tensor] = field(default_factory=dict)


def _profiles(values, n_model: int) -> tuple[np.ndarray, np.ndarray]:
    """(distinct register values, index of each model neuron's value) for an int or per-neuron register."""
    arr = np.broadcast_to(np.asarray(values, np.int64), (n_model,)) if np.ndim(values) == 0 else \
        np.asarray(values, np.int64)[:n_model]
    uniq, inv = np.unique(arr, return_inverse=True)
    return uniq, inv.reshape(-1)


def _delay_groups(delay, shape) -> list[tuple[int, np.ndarray | None]]:
    """[(delay d, mask of synapses with delay d, or None for all)]."""
    d = np.asarray(delay, np.int64)
    if d.size <= 1:
        return [(int(d.reshape(-1)[0]) if d.size else 0, None)]
    d = np.broadcast_to(d, shape)
    return [(int(v), d == v) for v in np.unique(d)]


def _shift_time(x: torch.Tensor, k: int) -> torch.Tensor:
    """x[:, t - k] along time (zeros for t < k)."""
    if k == 0:
        return x
    out = torch.zeros_like(x)
    if k < x.shape[1]:
        out[:, k:] = x[:, :-k]
    return out


class _Projection(torch.nn.Module):
    """One weight matrix: learnable half mantissas of the model's synapses, fixed structure around them."""

    def __init__(self, weight, wgt_exp, delay, rows: int, cols: int, term_cols: list[list[int]], learn: bool,
                 dtype, device):
        super().__init__()
        w = np.asarray(weight, np.int64)
        if np.any(w % 2):
            raise SnnccError("Loihi weight mantissas must be even", field="weight")
        self.shape = w.shape
        self.rows, self.cols = rows, cols
        self.term_cols = term_cols            # for each bias term: the source columns that repeat it
        half = w // 2
        self.model = torch.nn.Parameter(torch.as_tensor(half[:rows, :cols], dtype=dtype, device=device),
                                        requires_grad=learn)
        terms = np.stack([half[:rows, c[0]] for c in term_cols], axis=1) if term_cols else np.zeros((rows, 0))
        self.terms = torch.nn.Parameter(torch.as_tensor(terms, dtype=dtype, device=device), requires_grad=learn)
        self.register_buffer("fixed", torch.as_tensor(w, dtype=dtype, device=device))
        factor = np.broadcast_to(2.0 ** (chip.WEIGHT_SHIFT + np.asarray(wgt_exp, np.int64)), w.shape)
        self.register_buffer("factor", torch.as_tensor(np.array(factor), dtype=dtype, device=device))
        self.groups = [(d, None if m is None else torch.as_tensor(m, dtype=dtype, device=device))
                       for d, m in _delay_groups(delay, w.shape)]
        self.term_index = [(j, c) for j, cols_ in enumerate(term_cols) for c in cols_]
        if self.term_index and [c for _, c in self.term_index] != list(range(cols, self.shape[1])):
            raise SnnccError("internal check failed: bias-source columns must follow the model's columns",
                             field="weight")
        self.term_order = [j for j, _ in self.term_index]

    def mantissas(self) -> torch.Tensor:
        """The full (n, n_in) even integer mantissas (float tensor), straight-through in the shadows:
        the model's block, then the bias-term columns (or the fixed padding), then the fixed rows of
        always-on units (no synapse reaches them)."""
        top = 2.0 * torch.clamp(round_ste(self.model), HALF_MIN, HALF_MAX)
        if self.term_index:
            terms = 2.0 * torch.clamp(round_ste(self.terms), HALF_MIN, HALF_MAX)
            top = torch.cat([top, terms[:, self.term_order]], dim=1)
        elif self.cols < self.shape[1]:
            top = torch.cat([top, self.fixed[:self.rows, self.cols:]], dim=1)
        return torch.cat([top, self.fixed[self.rows:]], dim=0) if self.rows < self.shape[0] else top

    def chip_weights(self) -> list[tuple[int, torch.Tensor]]:
        """[(delay d, chip-unit weights with delay d)]."""
        w = self.mantissas() * self.factor
        return [(d, w if m is None else w * m) for d, m in self.groups]

    def project(self) -> None:
        with torch.no_grad():
            self.model.clamp_(HALF_MIN, HALF_MAX)
            self.terms.clamp_(HALF_MIN, HALF_MAX)

    def export(self, dtype) -> np.ndarray:
        with torch.no_grad():
            return self.mantissas().cpu().numpy().round().astype(np.int64).astype(dtype)


class _Register(torch.nn.Module):
    """A per-compartment register: one learnable value per profile of the model neurons, fixed values for
    the always-on sources; rounded to integers in [low, high]."""

    def __init__(self, values, n: int, n_model: int, low: int, high: int, learn: bool, dtype, device,
                 per_neuron: bool = False):
        super().__init__()
        uniq, inv = _profiles(values, n_model)
        if per_neuron:      # every model neuron its own value (a bias is a per-neuron register, not a profile)
            uniq = np.array(np.broadcast_to(np.asarray(values, np.int64), (n,))[:n_model])
            inv = np.arange(n_model)
        self.scalar = np.ndim(values) == 0
        self.low, self.high = low, high
        self.shadow = torch.nn.Parameter(torch.as_tensor(uniq, dtype=dtype, device=device), requires_grad=learn)
        self.register_buffer("index", torch.as_tensor(inv, dtype=torch.long, device=device))
        full = np.broadcast_to(np.asarray(values, np.int64), (n,)).astype(np.float64)
        self.register_buffer("sources", torch.as_tensor(full[n_model:], dtype=dtype, device=device))
        self.original_sources = full[n_model:].astype(np.int64)
        self.original_first = int(full[0]) if n else 0

    def values(self) -> torch.Tensor:
        """(n,) integer-valued register per compartment (straight-through in the shadows)."""
        model = torch.clamp(round_ste(self.shadow), self.low, self.high)[self.index]
        return torch.cat([model, self.sources]) if self.sources.numel() else model

    def project(self) -> None:
        with torch.no_grad():
            self.shadow.clamp_(self.low, self.high)

    def model_values(self) -> np.ndarray:
        with torch.no_grad():
            return torch.clamp(torch.round(self.shadow), self.low, self.high)[self.index].cpu().numpy().astype(np.int64)

    def export(self):
        """The register to write: an int when it was one profile, else one value per compartment; the
        always-on sources that shared neuron 0's profile follow its new value (no new profile)."""
        model = self.model_values()
        src = np.where(self.original_sources == self.original_first, model[0], self.original_sources) \
            if model.size else self.original_sources
        full = np.concatenate([model, src]).astype(np.int64)
        if self.scalar and full.size and np.all(full == full[0]):
            return int(full[0])
        if self.scalar:
            raise SnnccError("internal check failed: a one-profile register got several values", field="register")
        return full


def _term_columns(network: LoihiNetwork, i: int) -> list[list[int]]:
    """The bias-source columns of layer ``i``'s feed-forward matrix, grouped by the term they repeat."""
    pre, lay = network.layers[i - 1], network.layers[i]
    k = pre.always_on
    if not k:
        return []
    first = pre.n - k
    repeats = 1 if pre.kind == "input" else int(pre.ref_delay)
    w = np.asarray(lay.weight)
    if k % repeats or any(not np.array_equal(w[:, first + j], w[:, first + j - j % repeats]) for j in range(k)):
        repeats = 1
    return [list(range(first + t * repeats, first + (t + 1) * repeats)) for t in range(k // repeats)]


class DifferentiableLoihi(torch.nn.Module):
    """A LoihiNetwork's arithmetic as a torch module (see the module docstring).

    ``names``: the IR population of each layer 1..L; ``shifts``: population -> chip steps its spike
    train is delayed (the timing pass); ``steps``: the model's own steps T (the chip runs
    ``T + lead`` steps). ``learn``: which parameter kinds are trained ("weights", "thresholds",
    "decays", "biases")."""

    LEARNABLE = ("weights", "thresholds", "decays", "biases")

    def __init__(self, network: LoihiNetwork, names: list[str], shifts: dict[str, int], steps: int, *,
                 learn=LEARNABLE, slope: float = 5.0, detach_reset: bool = False, fused: bool = True,
                 dtype: torch.dtype = torch.float64, device: torch.device | str = "cpu"):
        super().__init__()
        unknown = set(learn) - set(self.LEARNABLE)
        if unknown:
            raise SnnccError(f"unknown parameter kinds {sorted(unknown)}; choose from {self.LEARNABLE}", field="learn")
        if len(names) != len(network.layers) - 1:
            raise SnnccError("one population name per layer is needed", field="names")
        self.network = network
        self.populations = tuple(names)
        self.shifts = {n: int(shifts.get(n, 0)) for n in names}
        self.steps = int(steps)
        self.lead = max(self.shifts.values(), default=0)
        self.slope = float(slope)
        self.detach_reset = bool(detach_reset)
        self.fused = bool(fused)
        self.dtype, self.device = dtype, torch.device(device)
        self.ff = torch.nn.ModuleList()
        self.rec = torch.nn.ModuleList()
        self.vth = torch.nn.ModuleList()
        self.idecay = torch.nn.ModuleList()
        self.vdecay = torch.nn.ModuleList()
        self.bias = torch.nn.ModuleList()
        self.has_bias: list[bool] = []
        for i, lay in enumerate(network.layers[1:], start=1):
            pre = network.layers[i - 1]
            m = lay.model_n
            self.ff.append(_Projection(lay.weight, lay.wgt_exp, lay.delay, m, pre.model_n, _term_columns(network, i),
                                       "weights" in learn, dtype, self.device))
            if lay.weight_rec is not None:
                self.rec.append(_Projection(lay.weight_rec, lay.wgt_exp_rec, lay.delay_rec, m, m, [],
                                            "weights" in learn, dtype, self.device))
            else:
                self.rec.append(torch.nn.Identity())
            self.vth.append(_Register(lay.v_th_mant, lay.n, m, chip.V_TH_MANT_MIN, chip.V_TH_MANT_MAX,
                                      "thresholds" in learn, dtype, self.device))
            self.idecay.append(_Register(lay.i_decay, lay.n, m, 0, chip.DECAY_ONE, "decays" in learn, dtype,
                                         self.device))
            self.vdecay.append(_Register(lay.v_decay, lay.n, m, 0, chip.DECAY_ONE, "decays" in learn, dtype,
                                         self.device))
            bias = np.zeros(lay.n, np.int64) if lay.bias is None else np.asarray(lay.bias, np.int64)
            learn_bias = "biases" in learn and bool(np.any(bias[:m] != 0))
            self.has_bias.append(lay.bias is not None)
            self.bias.append(_Register(bias, lay.n, m, -chip.BIAS_MANT_MAX, chip.BIAS_MANT_MAX, learn_bias, dtype,
                                       self.device, per_neuron=True))

    # -- the chip's arithmetic --------------------------------------------------------------------
    def run_chip(self, x: torch.Tensor, force: dict[str, torch.Tensor] | None = None, record: bool = False) -> ChipRun:
        """Run driven, padded inputs (B, T_chip, axons) in chip time. ``force``: population -> chip-time
        spikes (B, T_chip, model_n) read by every synapse leaving that population instead of its own."""
        x = x.to(dtype=self.dtype, device=self.device)
        batch, steps, _ = x.shape
        out = ChipRun()
        prev = x
        layers = self.network.layers
        for i, lay in enumerate(layers[1:], start=1):
            k = i - 1
            n, m = lay.n, lay.model_n
            name = self.populations[k]
            drive = None
            for d, w in self.ff[k].chip_weights():
                part = _shift_time(prev, 1 + d) @ w.T
                drive = part if drive is None else drive + part
            rec = self.rec[k].chip_weights() if lay.weight_rec is not None else []
            forced = None if force is None else force.get(name)
            keep_u = chip.DECAY_ONE - self.idecay[k].values()
            keep_v = chip.DECAY_ONE - self.vdecay[k].values()
            theta = self.vth[k].values() * float(1 << chip.V_TH_SHIFT)
            bias = self.bias[k].values() * float(2 ** lay.bias_exp) if self.has_bias[k] else None
            u = torch.zeros(batch, n, dtype=self.dtype, device=self.device)
            v = torch.zeros_like(u)
            ref = torch.zeros(batch, n, dtype=torch.int64, device=self.device)
            spikes, currents, volts, pres = [], [], [], []
            readable = []     # what synapses leaving this population read at each step
            zero = torch.zeros(batch, n, dtype=self.dtype, device=self.device)
            for t in range(steps):
                q = drive[:, t]
                for d, w in rec:
                    src = t - 1 - d
                    if src >= 0:
                        q = q + readable[src] @ w.T
                q = wrap_ste(q, chip.Q_BITS)
                u = wrap_ste(trunc_ste(u * keep_u / chip.DECAY_ONE) + q, chip.U_BITS)
                v = trunc_ste(v * keep_v / chip.DECAY_ONE) + u
                if bias is not None:
                    v = v + bias
                v = torch.clamp(v, float(lay.vmin), float(lay.vmax))
                refractory = ref > 0
                v = torch.where(refractory, zero, v)
                ref = torch.where(refractory, ref - 1, ref)
                s = spike(v, theta, self.slope)
                fired = s > 0
                pres.append(v)
                v = v * (1.0 - (s.detach() if self.detach_reset else s))
                ref = torch.where(fired, torch.full_like(ref, lay.ref_delay - 1), ref)
                spikes.append(s)
                if forced is not None:
                    readable.append(torch.cat([forced[:, t], s[:, m:]], dim=1) if n > m else forced[:, t])
                else:
                    readable.append(s)
                if record:
                    currents.append(u)
                    volts.append(v)
            out.spikes[i] = torch.stack(spikes, dim=1)
            out.voltage_pre[i] = torch.stack(pres, dim=1)
            out.threshold[i] = theta
            if record:
                out.current[i] = torch.stack(currents, dim=1)
                out.voltage[i] = torch.stack(volts, dim=1)
            prev = torch.stack(readable, dim=1)
        return out

    def run_fused(self, x: torch.Tensor, force: dict[str, torch.Tensor] | None = None) -> ChipRun:
        """``run_chip`` (spikes and pre-reset voltage only) with each layer's time loop one autograd
        function (``layer_bptt.LayerLoop``): the same values and gradients, several times faster."""
        from snncc.targets.loihi.finetune.layer_bptt import LayerLoop

        x = x.to(dtype=self.dtype, device=self.device)
        out = ChipRun()
        prev = x
        for i, lay in enumerate(self.network.layers[1:], start=1):
            k = i - 1
            n, m = lay.n, lay.model_n
            drive = None
            for d, w in self.ff[k].chip_weights():
                part = _shift_time(prev, 1 + d) @ w.T
                drive = part if drive is None else drive + part
            rec = self.rec[k].chip_weights() if lay.weight_rec is not None else []
            forced = None if force is None else force.get(self.populations[k])
            if forced is not None:
                forced = forced.detach()
                if n > m:   # no recurrent synapse leaves an always-on source: zeros stand in for them
                    forced = torch.cat([forced, forced.new_zeros(forced.shape[:2] + (n - m,))], dim=2)
            theta = self.vth[k].values() * float(1 << chip.V_TH_SHIFT)
            bias = self.bias[k].values() * float(2 ** lay.bias_exp) if self.has_bias[k] else \
                torch.zeros(n, dtype=self.dtype, device=self.device)
            cfg = (tuple(d for d, _ in rec), float(lay.vmin), float(lay.vmax), int(lay.ref_delay), self.slope,
                   self.detach_reset)
            spikes, v_pre = LayerLoop.apply(drive, chip.DECAY_ONE - self.idecay[k].values(),
                                            chip.DECAY_ONE - self.vdecay[k].values(), theta, bias,
                                            forced, cfg, *[w for _, w in rec])
            out.spikes[i], out.voltage_pre[i], out.threshold[i] = spikes, v_pre, theta
            prev = spikes if forced is None else torch.cat([forced[:, :, :m], spikes[:, :, m:]], dim=2)
        return out

    def drive(self, x: torch.Tensor) -> torch.Tensor:
        """Model-time inputs (B, T, C) -> chip-time (B, T + lead, axons): always-on axons at 1, blank lead steps."""
        x = x.to(dtype=self.dtype, device=self.device)
        k = self.network.layers[0].always_on
        if k:
            x = torch.cat([x, torch.ones(x.shape[:2] + (k,), dtype=self.dtype, device=self.device)], dim=2)
        if self.lead:
            pad = torch.zeros(x.shape[0], self.lead, x.shape[2], dtype=self.dtype, device=self.device)
            if k:
                pad[:, :, -k:] = 1.0
            x = torch.cat([x, pad], dim=1)
        return x

    def to_chip_time(self, name: str, spikes: torch.Tensor) -> torch.Tensor:
        """A population's model-time spikes (B, T, n) placed at its chip steps (B, T + lead, n)."""
        s = self.shifts[name]
        spikes = spikes.to(dtype=self.dtype, device=self.device)
        out = torch.zeros(spikes.shape[0], self.steps + self.lead, spikes.shape[2], dtype=self.dtype,
                          device=self.device)
        out[:, s:s + spikes.shape[1]] = spikes
        return out

    def forward(self, x: torch.Tensor, force: dict[str, torch.Tensor] | None = None) -> StudentRun:
        """Model-time inputs (B, T, C) -> output counts and each population's spikes and v / threshold
        (pre-reset) in model time, model neurons only. ``force``: population -> model-time spikes read by
        the synapses leaving it (teacher forcing)."""
        if x.shape[1] != self.steps:
            raise SnnccError(f"inputs have {x.shape[1]} steps, the student was built for {self.steps}", field="inputs")
        chip_force = None if not force else {k: self.to_chip_time(k, v) for k, v in force.items()}
        run = (self.run_fused if self.fused else self.run_chip)(self.drive(x), chip_force)
        spikes, voltage = {}, {}
        for i, name in enumerate(self.populations, start=1):
            s, m = self.shifts[name], self.network.layers[i].model_n
            spikes[name] = run.spikes[i][:, s:s + self.steps, :m]
            voltage[name] = run.voltage_pre[i][:, s:s + self.steps, :m] / run.threshold[i][:m]
        last = self.populations[-1]
        return StudentRun(counts=spikes[last].sum(dim=1), spikes=spikes, voltage=voltage)

    def swap_decays(self, k: int) -> None:
        """Exchange layer ``k``'s current and voltage decay registers (iDecay <-> vDecay).

        Below threshold a CUBA compartment's response to its input is symmetric in the two decays
        (the impulse response from q to v is (a**(t+1) - b**(t+1)) / (a - b), a = 1 - iDecay/4096,
        b = 1 - vDecay/4096), so the swap changes only what a reset to zero discards: v loses its
        state at every spike, u keeps it. With the slower decay on u, less is lost."""
        self.idecay[k], self.vdecay[k] = self.vdecay[k], self.idecay[k]

    # -- parameters ---------------------------------------------------------------------------------
    def param_groups(self) -> dict[str, list[torch.nn.Parameter]]:
        """Trainable parameters by kind (an optimiser gives each kind its own step size)."""
        groups = {"weights": [], "thresholds": [], "decays": [], "biases": []}
        for k in range(len(self.populations)):
            groups["weights"] += [self.ff[k].model, self.ff[k].terms]
            if isinstance(self.rec[k], _Projection):
                groups["weights"] += [self.rec[k].model]
            groups["thresholds"].append(self.vth[k].shadow)
            groups["decays"] += [self.idecay[k].shadow, self.vdecay[k].shadow]
            groups["biases"].append(self.bias[k].shadow)
        return {g: [p for p in ps if p.requires_grad and p.numel()] for g, ps in groups.items()}

    def project(self) -> None:
        """Clamp every shadow into its register's range (after each optimiser step)."""
        for k in range(len(self.populations)):
            self.ff[k].project()
            if isinstance(self.rec[k], _Projection):
                self.rec[k].project()
            for reg in (self.vth[k], self.idecay[k], self.vdecay[k], self.bias[k]):
                reg.project()

    # -- the registers to deploy --------------------------------------------------------------------
    def export(self) -> LoihiNetwork:
        """The network with the rounded registers (a new LoihiNetwork; the original is not changed)."""
        net = copy.deepcopy(self.network)
        for k, lay in enumerate(net.layers[1:]):
            lay.weight = self.ff[k].export(np.asarray(lay.weight).dtype)
            if lay.weight_rec is not None:
                lay.weight_rec = self.rec[k].export(np.asarray(lay.weight_rec).dtype)
            m = lay.model_n
            vth = self.vth[k].model_values()
            lay.i_decay = self.idecay[k].export()
            lay.v_decay = self.vdecay[k].export()
            old_vth = lay.v_th_mant
            lay.v_th_mant = _register(lay.v_th_mant, vth, lay.n)
            if self.has_bias[k]:
                bias = np.asarray(lay.bias, np.int64).copy()
                bias[:m] = self.bias[k].model_values()
                lay.bias = bias
            if lay.always_on:
                _keep_sources_firing(lay, old_vth)
        return net


def _register(old, model_values: np.ndarray, n: int):
    """A register with new values for the model neurons: an int stays an int (one profile)."""
    if np.ndim(old) == 0:
        if not np.all(model_values == model_values[0]):
            raise SnnccError("internal check failed: a one-profile register got several values", field="register")
        return int(model_values[0])
    arr = np.asarray(old, np.int64).copy()
    m = model_values.size
    arr[:m] = model_values
    if n > m:   # always-on sources reuse neuron 0's profile (bias_sources.py) where they did before
        src = np.asarray(old, np.int64)[m:]
        arr[m:] = np.where(src == np.asarray(old, np.int64)[0], arr[0], src)
    return arr


def _keep_sources_firing(lay: LoihiLayer, old_vth) -> None:
    """Always-on sources (the layer's last ``always_on`` units) must still fire on every free step:
    those that shared the layer's top threshold follow the new one; their bias is raised above it
    (``bias_sources.source_bias``), or they get their own threshold 1 when the 13-bit mantissa cannot."""
    m = lay.model_n
    old = np.broadcast_to(np.asarray(old_vth, np.int64), (lay.n,))
    new = np.broadcast_to(np.asarray(lay.v_th_mant, np.int64), (lay.n,)).copy()
    shared = old[m:] == old[:m].max()
    new[m:] = np.where(shared, new[:m].max(), old[m:])
    bias = np.asarray(lay.bias, np.int64).copy()
    exp = int(lay.bias_exp)
    for j in range(m, lay.n):
        if (int(bias[j]) << exp) > (int(new[j]) << chip.V_TH_SHIFT):
            continue
        mant = ((int(new[j]) << chip.V_TH_SHIFT) >> exp) + 1
        if mant > chip.BIAS_MANT_MAX:
            new[j] = chip.V_TH_MANT_MIN
            mant = ((chip.V_TH_MANT_MIN << chip.V_TH_SHIFT) >> exp) + 1
        bias[j] = mant
    lay.bias = bias
    lay.v_th_mant = int(new[0]) if np.ndim(lay.v_th_mant) == 0 and np.all(new == new[0]) else new
