"""The loss and schedule experiments behind snncc's deployment fine-tuning (docs/finetune.md). Long: not a test.

One variant per run, e.g. (the table in docs/finetune.md lists every run's arguments):

    python bench/studies/finetune_ablation.py --loss mse:1,hwin:1 --force-epochs 4 --epochs 12 --cosine --train 4096 \
        --val 500 --out r_f4.json
    python bench/studies/finetune_ablation.py --graph tests/data/nir/braille_zero_2023.nir --reset none --loss ce:1 \
        --tau 4 --epochs 8 --cosine --lr-w 0.03 --lr-th 0.05 --lr-d 0.3 --lr-b 0.1 --out z_ce.json

Inputs: ``--train + --val + --test`` seeded random spike trains (density 0.08, 256 steps; SYNTHETIC), drawn
in one call, the last ``--test`` held out. The student is ``DifferentiableLoihi`` on the graph lowered
with ``--rule`` (reset changed to zero); the teacher is the graph as loaded (its own reset). Loss terms
(``name:weight``): mse (output counts), ce (teacher argmax, clear winners), kl (softmaxed counts),
margin (squared hinge on the teacher's winner), hcount (hidden counts per neuron), hwin (hidden counts
in windows of --window steps), htrace (hidden spikes filtered with exp(-t/4)), volt / hvolt (V / theta
before reset, all / hidden populations). Agreement: the exported integers in the bit-exact emulator.
"""
import argparse, json, time, sys
import numpy as np, torch
torch.set_num_threads(1)
from snncc.frontends import LoadOptions, load_model
from snncc.targets.loihi.lowering.lower import lower_model
from snncc.targets.loihi.finetune.differentiable import DifferentiableLoihi
from snncc.targets.loihi.options import LoihiOptions
from snncc.targets.loihi.emulation.emulator import emulate
from snncc.targets.loihi.checks.exactness import lead_steps, pad, loihi_spikes
from snncc.finetune.teacher import run_teacher
from snncc.measure.agreement import argmax_agreement

ap = argparse.ArgumentParser()
ap.add_argument("--graph", default="tests/data/nir/braille_noDelay_noBias_subtract.nir")
ap.add_argument("--reset", default="subtract")
ap.add_argument("--rule", default="per-layer")
ap.add_argument("--train", type=int, default=1024)
ap.add_argument("--val", type=int, default=256)
ap.add_argument("--test", type=int, default=1000)
ap.add_argument("--density", type=float, default=0.08)
ap.add_argument("--steps", type=int, default=256)
ap.add_argument("--train-steps", type=int, default=0)
ap.add_argument("--epochs", type=int, default=6)
ap.add_argument("--batch", type=int, default=64)
ap.add_argument("--lr-w", type=float, default=0.3)
ap.add_argument("--lr-th", type=float, default=0.3)
ap.add_argument("--lr-d", type=float, default=3.0)
ap.add_argument("--lr-b", type=float, default=1.0)
ap.add_argument("--learn", default="weights,thresholds,decays,biases")
ap.add_argument("--loss", default="ce:1")  # comma list name:weight
ap.add_argument("--tau", type=float, default=2.0)
ap.add_argument("--window", type=int, default=16)
ap.add_argument("--cosine", action="store_true")
ap.add_argument("--swap", default="")
ap.add_argument("--perturb-th", type=float, default=1.0)
ap.add_argument("--margin", type=float, default=2.0)
ap.add_argument("--force-epochs", type=int, default=0)
ap.add_argument("--slope", type=float, default=5.0)
ap.add_argument("--detach-reset", action="store_true")
ap.add_argument("--seed", type=int, default=0)
ap.add_argument("--out", default=None)
a = ap.parse_args()

t0 = time.time(); c0 = time.process_time()
g = load_model(a.graph, LoadOptions(dt=1e-4, reset=None if a.reset == "none" else a.reset))
T = a.steps
low = lower_model(g, LoihiOptions(scale=a.rule, allow_reset_change=True), t_sample=T)
names = [c.lif for c in low.layers]
trec = low.timing_record
rng = np.random.default_rng(a.seed)
N = a.train + a.val + a.test
x = (rng.random((N, T, low.network.input_width)) < a.density).astype(np.uint8)
tr, va, te = np.arange(a.train), np.arange(a.train, a.train + a.val), np.arange(a.train + a.val, N)
teacher = run_teacher(g, x, tuple(names))
print("teacher", time.time() - t0, flush=True)

def emu_counts(net, xs):
    res = emulate(net, pad(xs, lead_steps(trec.shifts, trec.output_shift)), record="all")
    sp = loihi_spikes(res, net, low.layers, trec.shifts, T)
    return sp[names[-1]].sum(axis=1)

def evaluate(net):
    out = {}
    for nm, idx in (("val", va), ("test", te)):
        out[nm] = argmax_agreement(teacher.counts[idx], emu_counts(net, x[idx]))
    return out

st = DifferentiableLoihi(low.network, names, trec.shifts, T, learn=a.learn.split(","), slope=a.slope, detach_reset=a.detach_reset)
for k in [int(v) for v in a.swap.split(",") if v != ""]:
    st.swap_decays(k)
if a.perturb_th != 1.0:
    with torch.no_grad():
        for r in st.vth: r.shadow.mul_(a.perturb_th)
groups = st.param_groups()
lrs = {"weights": a.lr_w, "thresholds": a.lr_th, "decays": a.lr_d, "biases": a.lr_b}
opt = torch.optim.Adam([{"params": ps, "lr": lrs[k]} for k, ps in groups.items() if ps])
n_iter = a.epochs * ((a.train + a.batch - 1) // a.batch)
sched = torch.optim.lr_scheduler.LambdaLR(opt, lambda i: 0.5 * (1 + np.cos(np.pi * min(i, n_iter) / n_iter)) if a.cosine else 1.0)
losses = [(s.split(":")[0], float(s.split(":")[1])) for s in a.loss.split(",")]

def loss_fn(run, tb):
    total = 0.0
    ct = torch.as_tensor(tb.counts, dtype=torch.float64)
    cs = run.counts
    scale = ct.mean().clamp_min(1.0)
    for name, w in losses:
        if name == "mse":
            l = (((cs - ct) / scale) ** 2).mean()
        elif name == "ce":
            top = torch.sort(ct, dim=1).values
            clear = top[:, -1] > top[:, -2]
            l = torch.nn.functional.cross_entropy(cs[clear] / a.tau, ct[clear].argmax(1)) if clear.any() else cs.sum() * 0
        elif name == "margin":
            top = torch.sort(ct, dim=1).values
            clear = top[:, -1] > top[:, -2]
            w_ = ct.argmax(1)
            cw = cs.gather(1, w_[:, None])
            other = cs.masked_fill(torch.nn.functional.one_hot(w_, cs.shape[1]).bool(), -1e9)
            l = torch.relu(other - cw + a.margin).pow(2).sum(1)[clear].mean()
        elif name == "kl":
            l = torch.nn.functional.kl_div(torch.log_softmax(cs / a.tau, 1), torch.softmax(ct / a.tau, 1), reduction="batchmean")
        elif name == "hcount":
            l = 0
            for p in names[:-1]:
                hs = run.spikes[p].sum(1); ht = torch.as_tensor(tb.spikes[p].sum(1), dtype=torch.float64)
                l = l + (((hs - ht) / ht.mean().clamp_min(1.0)) ** 2).mean()
        elif name == "htrace":
            l = 0
            for p in names[:-1]:
                d = run.spikes[p] - torch.as_tensor(tb.spikes[p], dtype=torch.float64)
                # exponential filter, tau 4 steps, via cumulative loop-free conv
                k = torch.exp(-torch.arange(16, dtype=torch.float64) / 4.0)
                f = torch.nn.functional.conv1d(d.transpose(1, 2).reshape(-1, 1, d.shape[1]), k.flip(0).view(1, 1, -1), padding=15)[..., :d.shape[1]]
                l = l + (f ** 2).mean()
        elif name == "hwin":
            l = 0
            for p in names[:-1]:
                d = run.spikes[p] - torch.as_tensor(tb.spikes[p], dtype=torch.float64)
                B_, T_, n_ = d.shape
                wsz = a.window
                d = d[:, :T_ // wsz * wsz].reshape(B_, T_ // wsz, wsz, n_).sum(2)
                l = l + (d ** 2).mean()
        elif name == "volt":
            l = 0
            for p in names:
                vs = run.voltage[p].clamp(-2, 2); vt = torch.as_tensor(tb.voltage[p], dtype=torch.float64).clamp(-2, 2)
                l = l + ((vs - vt) ** 2).mean()
        elif name == "hvolt":
            l = 0
            for p in names[:-1]:
                vs = run.voltage[p].clamp(-2, 2); vt = torch.as_tensor(tb.voltage[p], dtype=torch.float64).clamp(-2, 2)
                l = l + ((vs - vt) ** 2).mean()
        total = total + w * l
    return total

hist = []
ev = evaluate(st.export())
print("before", ev["val"].text(), "| test", ev["test"].text(), flush=True)
hist.append({"epoch": 0, "val": ev["val"].share, "test": ev["test"].share})
best = (ev["val"].share, 0, {k: v.clone() for k, v in st.state_dict().items()})
it = 0
for ep in range(1, a.epochs + 1):
    perm = np.random.default_rng(a.seed + ep).permutation(tr)
    forced = ep <= a.force_epochs
    tl = 0
    for b0 in range(0, len(perm), a.batch):
        idx = perm[b0:b0 + a.batch]
        tb = teacher.select(idx)
        xb = torch.as_tensor(x[idx], dtype=torch.float64)
        force = {p: torch.as_tensor(tb.spikes[p], dtype=torch.float64) for p in names[:-1]} if forced else None
        run = st(xb, force=force)
        l = loss_fn(run, tb)
        opt.zero_grad(); l.backward(); opt.step(); sched.step(); st.project(); it += 1
        tl += float(l.detach())
    ev = evaluate(st.export())
    print(f"ep {ep} loss {tl:.3f} val {ev['val'].share:.3f} test {ev['test'].text()} t {time.time()-t0:.0f}s cpu {time.process_time()-c0:.0f}", flush=True)
    hist.append({"epoch": ep, "val": ev["val"].share, "test": ev["test"].share, "loss": tl})
    if ev["val"].share > best[0]:
        best = (ev["val"].share, ep, {k: v.clone() for k, v in st.state_dict().items()})
st.load_state_dict(best[2])
ev = evaluate(st.export())
print("vth", [float(r.shadow[0]) for r in st.vth], "idec", [float(r.shadow[0]) for r in st.idecay], "vdec", [float(r.shadow[0]) for r in st.vdecay])
print("BEST ep", best[1], "val", ev["val"].share, "test", ev["test"].text(), "time", time.time() - t0, "cpu", time.process_time() - c0)
if a.out:
    json.dump({"args": vars(a), "hist": hist, "best_epoch": best[1], "test": ev["test"].as_dict(), "time": time.time() - t0, "cpu": time.process_time() - c0}, open(a.out, "w"), indent=1)
