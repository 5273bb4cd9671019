"""Does Intel's toolchain run snncc's Loihi bundles as snncc emulates them? lava-dl netx 0.6 + Lava fixed_pt.

    python bench/studies/lava_netx_agreement.py                  # everything: ~15-25 min on 2 cores, first run + venv build
    python bench/studies/lava_netx_agreement.py --quick          # 2 samples, the small graphs only
    python bench/studies/lava_netx_agreement.py --graphs braille_zero_2023 --rules global auto --timings exact
    python bench/studies/lava_netx_agreement.py --graphs braille_zero_2023 --rules per-layer --timings exact --replicas 4 \
        --no-probes [--finetune] --out bench/studies/results/lava_netx_agreement_replicas.json

Not run in CI. Steps:

1. Builds (once; reused while ``bench/studies/lava_requirements.txt`` is unchanged) a Python 3.10
   virtualenv at ``--venv`` (default ``bench/studies/.lava-venv``, git-ignored) with the exact pins of
   ``bench/studies/lava_requirements.txt``: lava-dl 0.6.0, lava-nc 0.10.0 and what they need (torch 2.3.1
   from PyPI: the only torch lava-dl 0.6.0 accepts; PyPI's Linux wheel is the CUDA build, so the
   venv is ~5.6 GB; it runs on the CPU). Python 3.10 is ``--python310`` (default: pyenv's 3.10.13,
   else ``python3.10`` on PATH).
2. Compiles, in this (snncc's) environment with ``snncc.api.compile``, every graph of
   ``--nir-dir`` (default ``../shared/nir`` beside the repository, else ``tests/data/nir``) that
   compiles for Loihi, and an authors'-layout RSNN (a SpyTorch weight list 48 -> 450 recurrent ->
   28 with the th1 parameters file, nb_input_copies 2; SYNTHETIC seeded weights: the authors'
   initialisation with the feed-forward weights x 2 and the recurrent ones x 0.2 so that it spikes),
   under every scale rule (global, per-layer, split, fine, auto) and both timing modes (exact,
   paper). A rule or mode compile refuses is recorded with its one-line reason.
3. For each bundle: seeded random 0/1 inputs of the bundle's full tSample (SYNTHETIC), run with
   ``snncc.api.emulate(..., record="all")`` and, in the 3.10 venv, with ``bench/studies/lava_runner.py``
   (``lava.lib.dl.netx.hdf5.Network`` fed by a ``RingBuffer`` source, ``Loihi1SimCfg(select_tag=
   "fixed_pt")``; the always-on bias axons of /layer/0/alwaysOn held at 1 by the driver, as a
   Lava driver of such a bundle must). Output and hidden spikes, and every layer's u and v, are
   compared step for step (the model's units; always-on bias compartments are left out).
4. ``--probes`` (on by default): small seeded networks written with snncc's bundle writer, each
   with ONE bundle feature switched on (a weight exponent, per-synapse exponents, a bias exponent,
   refDelay, delays, per-neuron registers, always-on sources, overflow ...), run the same way, so
   each feature's verdict stands on its own.

Writes ``--out`` (default ``bench/studies/results/lava_netx_agreement.json``) and prints the table. The
inputs and the probe weights are SYNTHETIC (seeded); the NIR graphs' weights are the trained ones.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[2]
BENCH = REPO / "bench" / "studies"
RUNNER = BENCH / "lava_runner.py"
REQUIREMENTS = BENCH / "lava_requirements.txt"
DEFAULT_VENV = BENCH / ".lava-venv"
RULES = ("global", "per-layer", "split", "fine", "auto")
TIMINGS = ("exact", "paper")
TH1 = ("scale 5\ntime_bin_size 5\nnb_input_copies 2\ntau_mem 0.06\ntau_ratio 10\nfwd_weight_scale 1\n"
       "weight_scale_factor 0.01\nreg_spikes 0.004\nreg_neurons 1e-6\n")


@dataclass
class Case:
    """One model to compile: a file, snncc.api.compile options, and its input density."""

    name: str
    path: Path
    options: dict[str, Any]
    density: float
    params: Path | None = None
    copies: int = 1            # the bundle's input copies (authors' RSNN: each event channel fed twice)
    quick: bool = True
    max_samples: int | None = None   # a cap for large models (Lava's Python simulation is slow)


@dataclass
class Row:
    case: str
    rule: str
    timing: str
    compiled: bool = False
    compile_error: str = ""
    bundle: str = ""
    layer_sha256: str = ""
    chosen: str = ""                      # the quantization record's reason (auto: the candidate chosen)
    features: dict[str, Any] = field(default_factory=dict)
    netx_compat: list[str] = field(default_factory=list)
    result: dict[str, Any] = field(default_factory=dict)


# -- the 3.10 venv ---------------------------------------------------------------------------------
def find_python310(given: str | None) -> str:
    for cand in ([given] if given else []) + [str(Path.home() / ".pyenv/versions/3.10.13/bin/python3.10"),
                                              shutil.which("python3.10") or ""]:
        if cand and Path(cand).exists():
            return cand
    sys.exit("lava_netx_agreement: error: --python310: no Python 3.10 found (lava-dl 0.6.0 requires 3.10); "
             "pass --python310 /path/to/python3.10")


def ensure_venv(venv: Path, python310: str) -> Path:
    """The venv's python, building the venv from lava_requirements.txt unless its stamp matches."""
    py = venv / "bin" / "python"
    want = hashlib.sha256(REQUIREMENTS.read_bytes()).hexdigest()
    stamp = venv / ".snncc-lava-stamp"
    if py.exists() and stamp.exists() and stamp.read_text().strip() == want:
        return py
    print(f"building the lava venv at {venv} (Python 3.10, {REQUIREMENTS.name}; several GB, minutes) ...", flush=True)
    t0 = time.perf_counter()
    if venv.exists():
        shutil.rmtree(venv)
    subprocess.run([python310, "-m", "venv", str(venv)], check=True)
    subprocess.run([str(py), "-m", "pip", "install", "-q", "-r", str(REQUIREMENTS)], check=True)
    subprocess.run([str(py), "-c", "import lava.lib.dl.netx, lava.magma.core.run_configs"], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    stamp.write_text(want + "\n")
    print(f"  built in {time.perf_counter() - t0:.0f} s", flush=True)
    return py


def venv_versions(py: Path) -> dict[str, str]:
    code = ("import json, importlib.metadata as m, platform; print(json.dumps({'python': platform.python_version(), "
            "**{p: m.version(p) for p in ('lava-dl', 'lava-nc', 'torch', 'numpy', 'h5py', 'scipy')}}))")
    out = subprocess.run([str(py), "-c", code], check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


# -- the cases -------------------------------------------------------------------------------------
def nir_dir(given: str | None) -> Path:
    for cand in ([Path(given)] if given else []) + [REPO.parent / "shared" / "nir", Path("/work/shared/nir"),
                                                    REPO / "tests" / "data" / "nir"]:
        if cand.is_dir() and any(cand.glob("*.nir")):
            return cand
    sys.exit("lava_netx_agreement: error: --nir-dir: no directory of .nir graphs found")


def authors_rsnn(work: Path, seed: int) -> tuple[Path, Path]:
    """A SpyTorch weight list [W_in 48x450, W_out 450x28, V_rec 450x450] + th1 parameters (SYNTHETIC)."""
    import torch

    g = torch.Generator().manual_seed(seed)
    w_in = torch.randn(48, 450, generator=g) * 2.0 / 48 ** 0.5
    w_out = torch.randn(450, 28, generator=g) * 2.0 / 450 ** 0.5
    v_rec = torch.randn(450, 450, generator=g) * 0.2 / 450 ** 0.5
    weights, params = work / "rsnn_weights_th1.pt", work / "rsnn_parameters_th1.txt"
    torch.save([w_in, w_out, v_rec], weights)
    params.write_text(TH1)
    return weights, params


def cases(nir: Path, work: Path, seed: int) -> list[Case]:
    """Every graph of ``nir`` with the options docs/nir.md gives it, and the authors' RSNN."""
    known = {
        "braille_zero_2023": ({"dt": 1e-4}, 0.08, True),
        "braille_noDelay_noBias_subtract": ({"dt": 1e-4, "reset": "subtract", "allow_reset_change": True}, 0.08, True),
        "braille_subgraph_2023": ({"dt": 1e-4}, 0.08, False),
        "cnn_sinabs": ({}, 0.05, False),      # 2,312 -> 4,096 -> 4,096 -> 512 -> 256 -> 10: minutes per sample in Lava
        "lif_norse": ({"dt": 1e-4}, 0.2, True),
        "lif_rockpool": ({}, 0.2, True),
        "two_lif_neurons": ({"dt": 1e-4}, 0.2, True),
    }
    out = []
    for path in sorted(nir.glob("*.nir")):
        options, density, quick = known.get(path.stem, ({}, 0.05, False))
        out.append(Case(path.stem, path, options, density, quick=quick,
                        max_samples=2 if path.stem == "cnn_sinabs" else None))
    weights, params = authors_rsnn(work, seed)
    out.append(Case("rsnn_authors_th1", weights, {}, 0.02, params=params, copies=2, quick=False))
    return out


# -- bundle facts ----------------------------------------------------------------------------------
def layer_digest(bundle: Path) -> str:
    """SHA-256 of every dataset under /layer (what netx and the emulator read), in a fixed order."""
    import h5py

    h = hashlib.sha256()
    with h5py.File(bundle, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                h.update(name.encode())
                h.update(np.ascontiguousarray(obj[()]).tobytes())
        f["layer"].visititems(visit)
        h.update(np.asarray(f["simulation/tSample"][()]).tobytes())
    return h.hexdigest()


def exponent_text(exp) -> Any:
    e = np.asarray(exp)
    if e.ndim == 0:
        return int(e)
    return {"per_synapse": sorted(set(np.unique(e).tolist()))}


def features(bundle: Path) -> tuple[dict[str, Any], list[str], str]:
    """What the bundle states, layer by layer (the fields netx might read), its netx_compat notes and rule."""
    import h5py

    from snncc.targets.loihi.bundle.read import read_bundle

    net = read_bundle(bundle)
    layers = []
    for i, lay in enumerate(net.layers[1:], start=1):
        d = np.asarray(lay.delay)
        entry = {
            "n": lay.n, "kind": lay.kind, "always_on": lay.always_on,
            "wgtExp": exponent_text(lay.wgt_exp),
            "weight_max_abs": int(np.abs(lay.weight).max(initial=0)),
            # Lava clips each synapse matrix by its own sign mode: an all-negative one to -255 (see docs)
            "inhibitory_with_min": [name for name, w in (("weight", lay.weight), ("weight_rec", lay.weight_rec))
                                    if w is not None and w.size and w.max() <= 0 and w.min() == -256],
            "delay_max": int(d.max(initial=0)),
            "refDelay": int(lay.ref_delay),
            "bias": lay.bias is not None,
            "per_neuron": [k for k, v in (("vThMant", lay.v_th_mant), ("iDecay", lay.i_decay), ("vDecay", lay.v_decay))
                           if np.ndim(v)],
        }
        if lay.bias is not None:
            entry["biasExp"] = int(lay.bias_exp)
        if lay.weight_rec is not None:
            entry["wgtExpRec"] = exponent_text(lay.wgt_exp_rec)
            entry["delay_rec_max"] = int(np.asarray(lay.delay_rec).max(initial=0))
        layers.append(entry)
    with h5py.File(bundle, "r") as f:
        compat = json.loads(f["snncc/netx_compat"][()].reshape(-1)[0]) if "snncc/netx_compat" in f else []
        quant = json.loads(f["snncc/quantization"][()].reshape(-1)[0]) if "snncc/quantization" in f else {}
        timing = json.loads(f["snncc/timing"][()].reshape(-1)[0]) if "snncc/timing" in f else {}
    facts = {"t_sample": net.t_sample, "input_axons": net.layers[0].n, "input_always_on": net.layers[0].always_on,
             "output_shift": int(net.metadata.get("output_shift", 0) or 0), "layers": layers,
             "timing_changes": timing.get("changes", [])}
    return facts, compat, str(quant.get("reason", ""))


def predicted_differences(facts: dict[str, Any], overflow: dict[str, int] | None = None) -> tuple[list[str], list[str]]:
    """(differences, caveats): what netx 0.6 + Lava fixed_pt ignore or read differently in this bundle
    (docs/lava_netx.md's definition of a netx-runnable bundle), and what runs identically only under a
    condition. ``overflow``: snncc's overflow counts on the inputs used (q wraps that Lava does not make)."""
    why, caveats = [], []
    if facts["input_always_on"]:
        caveats.append(f"{facts['input_always_on']} always-on input axon(s): identical only if the driver holds them at 1")
    for i, lay in enumerate(facts["layers"], start=1):
        e = lay["wgtExp"]
        if isinstance(e, dict):
            why.append(f"layer {i}: per-synapse wgtExp {e['per_synapse']} (netx ignores wgtExp: runs every weight as wgtExp 0)")
        elif e != 0:
            why.append(f"layer {i}: wgtExp {e} (netx ignores it: weights run {2.0 ** -e:g}x too {'large' if e < 0 else 'small'})")
        er = lay.get("wgtExpRec", 0)
        if isinstance(er, dict) or er != 0:
            why.append(f"layer {i}: wgtExpRec {er} (netx ignores it)")
        if lay.get("bias") and lay.get("biasExp", 6) != 6:
            why.append(f"layer {i}: biasExp {lay['biasExp']} (netx runs every bias with exponent 6)")
        if lay["refDelay"] != 1:
            why.append(f"layer {i}: refDelay {lay['refDelay']} (netx's LIF has no refractory period)")
        if lay.get("delay_rec_max", 0):
            why.append(f"layer {i}: delay_rec up to {lay['delay_rec_max']} (netx ignores it)")
        if lay["kind"] == "dense_rec" and lay["delay_max"]:
            why.append(f"layer {i}: feed-forward delays on a recurrent layer (netx gives its recurrent synapse the "
                       "feed-forward delay matrix and no weight exponent)")
        if lay["per_neuron"]:
            caveats.append(f"layer {i}: per-neuron {lay['per_neuron']} (Lava's LIF declares one value; its CPU model "
                           "broadcasts the array)")
        if lay["always_on"] and lay["refDelay"] != 1:
            why.append(f"layer {i}: {lay['always_on']} always-on bias compartment(s) timed by refDelay")
        if lay.get("inhibitory_with_min"):
            why.append(f"layer {i}: {lay['inhibitory_with_min']} all <= 0 and holding -256 (Lava clips it to -255, "
                       "then truncates it with netx's bit count)")
        if lay["weight_max_abs"] == 0 and lay["kind"] == "dense":
            why.append(f"layer {i}: every weight 0 (netx's optimize_weight_bits divides by max|W|: load error)")
    if overflow and overflow.get("overflow_q_wrap"):
        why.append(f"q wrapped {overflow['overflow_q_wrap']} time(s) in snncc (21 bits + sign); Lava does not wrap q")
    if overflow and overflow.get("u_at_minus_2pow23"):
        why.append(f"u = -2**23 {overflow['u_at_minus_2pow23']} time(s) in snncc; Lava's wrap turns it into +2**23")
    return why, caveats


# -- running both sides ----------------------------------------------------------------------------
def make_inputs(rows_for_bundle: Row, case: Case, facts: dict[str, Any], samples: int, seed: int) -> np.ndarray:
    """(B, tSample, model channels) 0/1, seeded; the authors' RSNN: 24 event channels tiled x copies."""
    width = facts["input_axons"] - facts["input_always_on"]
    base = width // case.copies
    rng = np.random.default_rng([seed, int(hashlib.sha256(case.name.encode()).hexdigest()[:8], 16)])
    x = (rng.random((samples, facts["t_sample"], base)) < case.density).astype(np.uint8)
    return np.tile(x, (1, 1, case.copies)) if case.copies > 1 else x


def run_lava(py: Path, jobs: list[dict[str, str]], timeout: float) -> dict[str, str]:
    """Run the jobs in one runner process; a job left without output (a crash) is retried alone.
    Returns job output path -> a one-line runner failure (empty when the job wrote its file)."""
    failures: dict[str, str] = {}
    if not jobs:
        return failures
    env = dict(os.environ, PYTHONWARNINGS="ignore")

    def call(batch: list[dict[str, str]]) -> str:
        with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
            json.dump(batch, f)
        try:
            p = subprocess.run([str(py), str(RUNNER), f.name], capture_output=True, text=True, timeout=timeout, env=env)
            return "" if p.returncode == 0 else (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1]
        except subprocess.TimeoutExpired:
            return f"runner timed out after {timeout:.0f} s"
        finally:
            os.unlink(f.name)

    err = call(jobs)
    for job in jobs:
        if not Path(job["output"]).exists():
            err = call([job]) or err
            if not Path(job["output"]).exists():
                failures[job["output"]] = err or "runner wrote nothing"
    return failures


def first_difference(a: np.ndarray, b: np.ndarray) -> dict[str, int] | None:
    diff = np.argwhere(a != b)
    if not diff.size:
        return None
    idx = diff[np.lexsort((diff[:, 2], diff[:, 0], diff[:, 1]))][0]   # earliest step first
    return {"sample": int(idx[0]), "step": int(idx[1]), "neuron": int(idx[2]),
            "lava": int(a[tuple(idx)]), "snncc": int(b[tuple(idx)])}


def compare(snn: dict[str, np.ndarray], lava: dict[str, np.ndarray], facts: dict[str, Any]) -> dict[str, Any]:
    """Per layer: spikes (and u, v) of the model's units, Lava against snncc emulate, step for step."""
    layers, all_spikes, all_state = [], True, True
    n_layers = len(facts["layers"])
    for k in range(1, n_layers + 1):
        entry: dict[str, Any] = {"layer": k, "output": k == n_layers}
        for field_name in ("spikes", "current", "voltage"):
            key = f"layer{k}_{field_name}"
            if key not in snn or key not in lava:
                entry[field_name] = {"identical": None, "note": "not recorded"}
                continue
            b = snn[key]
            a = lava[key][..., :b.shape[2]]
            same = bool(np.array_equal(a, b))
            item: dict[str, Any] = {"identical": same}
            if field_name == "spikes":
                item["equal_fraction"] = float(np.mean(a == b))
                item["spikes_snncc"] = int(b.sum())
                item["spikes_lava"] = int(a.sum())
                all_spikes &= same
            else:
                all_state &= same
            if not same:
                item["first_difference"] = first_difference(a, b)
            entry[field_name] = item
        layers.append(entry)
    out = layers[-1]["spikes"]
    return {"output_identical": out["identical"], "output_equal_fraction": out.get("equal_fraction"),
            "output_first_difference": out.get("first_difference"), "all_spikes_identical": all_spikes,
            "all_state_identical": all_state, "layers": layers}


def emulate_snncc(bundle: Path, x: np.ndarray, work: Path, tag: str) -> dict[str, np.ndarray]:
    import snncc.api as api

    xin, out = work / f"{tag}_x.npy", work / f"{tag}_snncc.npz"
    np.save(xin, x)
    api.emulate(str(bundle), input=str(xin), output=str(out), record="all")
    with np.load(out, allow_pickle=False) as z:
        result = {k: z[k] for k in z.files}
    return result


def drive(bundle: Path, x: np.ndarray) -> np.ndarray:
    from snncc.targets.loihi.bundle.read import read_bundle

    return read_bundle(bundle).drive(x)


# -- probes: one feature at a time -----------------------------------------------------------------
def probe_networks(seed: int):
    """(name, feature, LoihiNetwork, density) for small seeded networks, each with one feature switched on."""
    from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork

    rng = np.random.default_rng(seed)
    n_in, n_h, n_out, steps = 12, 20, 5, 64

    def even(shape, high):
        return (rng.integers(-high // 2, high // 2 + 1, size=shape) * 2).astype(np.int16)

    w1, wr, w2 = even((n_h, n_in), 254), even((n_h, n_h), 60), even((n_out, n_h), 200)

    def base(**changes):
        hid = LoihiLayer("hidden", "dense_rec", n_h, weight=w1.copy(), weight_rec=wr.copy(), v_th_mant=200,
                         i_decay=1024, v_decay=256)
        out = LoihiLayer("out", "dense", n_out, weight=w2.copy(), v_th_mant=150, i_decay=2048, v_decay=512)
        inp = LoihiLayer("input", "input", n_in)
        for key, value in changes.items():
            layer, attr = key.split("__")
            setattr({"hid": hid, "out": out, "inp": inp}[layer], attr, value(hid, out, inp) if callable(value) else value)
        return LoihiNetwork([inp, hid, out], steps, metadata={"probe": True})

    probes = [
        ("baseline", "wgtExp 0, no bias, no delay, refDelay 1, one register value per layer", base(), 0.15),
        ("wgtExp_minus2", "hidden wgtExp -2 (one exponent for the projection)", base(hid__wgt_exp=-2, hid__wgt_exp_rec=-2,
                                                                                     hid__v_th_mant=50), 0.15),
        ("wgtExp_plus1", "output wgtExp +1", base(out__wgt_exp=1, out__v_th_mant=300), 0.15),
        ("wgtExp_per_synapse", "hidden feed-forward exponents per synapse (-1 / 0)",
         base(hid__wgt_exp=lambda h, o, i: np.where(rng.random(h.weight.shape) < 0.5, -1, 0).astype(np.int64)), 0.15),
        ("wgtExpRec_only", "recurrent exponent -1, feed-forward 0", base(hid__wgt_exp_rec=-1), 0.15),
        ("small_weights", "max|W| 40 (netx rescales by its own weight exponent)",
         base(hid__weight=lambda h, o, i: (h.weight // 12) * 2, hid__v_th_mant=20), 0.3),
        ("excitatory_only", "all feed-forward weights >= 0",
         base(hid__weight=lambda h, o, i: np.abs(h.weight), hid__v_th_mant=400), 0.15),
        ("bias_exp6", "a voltage bias with biasExp 6 (netx's)",
         base(hid__bias=lambda h, o, i: rng.integers(-3, 4, h.n).astype(np.int64), hid__bias_exp=6), 0.15),
        ("bias_exp3", "a voltage bias with biasExp 3",
         base(hid__bias=lambda h, o, i: rng.integers(-40, 60, h.n).astype(np.int64), hid__bias_exp=3), 0.15),
        ("refDelay3", "hidden refDelay 3", base(hid__ref_delay=3), 0.15),
        ("delay_ff_dense", "output layer (dense): synaptic delays 0..3 per synapse",
         base(out__delay=lambda h, o, i: rng.integers(0, 4, o.weight.shape).astype(np.int64)), 0.15),
        ("delay_ff_uniform_dense", "output layer (dense): one delay 2", base(out__delay=2), 0.15),
        ("delay_ff_rec_layer", "hidden (dense_rec) feed-forward delay 1",
         base(hid__delay=1), 0.15),
        ("delay_rec", "hidden recurrent delay 1", base(hid__delay_rec=1), 0.15),
        ("per_neuron_vth", "hidden vThMant per neuron",
         base(hid__v_th_mant=lambda h, o, i: rng.integers(120, 300, h.n).astype(np.int64)), 0.15),
        ("per_neuron_idecay", "hidden iDecay per neuron",
         base(hid__i_decay=lambda h, o, i: rng.integers(200, 3000, h.n).astype(np.int64)), 0.15),
        ("per_neuron_vdecay", "hidden vDecay per neuron",
         base(hid__v_decay=lambda h, o, i: rng.integers(100, 1000, h.n).astype(np.int64)), 0.15),
        ("decays_0_4096", "iDecay 0 and vDecay 4096 (hidden), iDecay 4096 and vDecay 0 (output)",
         base(hid__i_decay=0, hid__v_decay=4096, out__i_decay=4096, out__v_decay=0, out__v_th_mant=400), 0.15),
        ("always_on_input", "/layer/0/alwaysOn = 1 (a current bias through an always-on input axon, driver holds it at 1)",
         base(inp__n=n_in + 1, inp__always_on=1,
              hid__weight=lambda h, o, i: np.concatenate([h.weight, even((n_h, 1), 100)], axis=1)), 0.15),
        ("always_on_hidden_ref2", "hidden layer's last unit a self-firing bias source with refDelay 2",
         base(hid__n=n_h + 1, hid__always_on=1, hid__ref_delay=2,
              hid__weight=lambda h, o, i: np.concatenate([h.weight, np.zeros((1, n_in), np.int16)], axis=0),
              hid__weight_rec=lambda h, o, i: np.pad(h.weight_rec, ((0, 1), (0, 1))),
              hid__bias=lambda h, o, i: np.r_[np.zeros(n_h, np.int64), 4000].astype(np.int64), hid__bias_exp=6,
              out__weight=lambda h, o, i: np.concatenate([o.weight, even((n_out, 1), 100)], axis=1)), 0.15),
        ("zero_weights_rec", "an all-zero recurrent matrix (feed-forward non-zero)",
         base(hid__weight_rec=lambda h, o, i: np.zeros_like(h.weight_rec)), 0.15),
        ("zero_weights_dense", "an all-zero feed-forward matrix into a dense layer",
         base(out__weight=lambda h, o, i: np.zeros_like(o.weight)), 0.15),
        ("inhibitory_with_min", "an inhibitory-only matrix (every weight < 0) that holds -256",
         base(out__weight=lambda h, o, i: np.where(np.abs(o.weight) > 100, -256, -np.abs(o.weight) - 2).astype(np.int16)),
         0.15),
        ("overflow_u_v", "u wraps and v clips (wgtExp 0, strong input, no decay, threshold at the 17-bit maximum)",
         base(hid__weight=lambda h, o, i: np.full_like(h.weight, 254), hid__weight_rec=lambda h, o, i: np.full_like(h.weight_rec, 254),
              hid__i_decay=0, hid__v_decay=0, hid__v_th_mant=2**17 - 1), 0.9),
    ]
    wide = 160     # q beyond its 21 bits + sign: ~152 of 160 inputs x 254 x 2**6 > 2**21 in one step
    q_in = LoihiLayer("input", "input", wide)
    q_hid = LoihiLayer("hidden", "dense", 8, weight=np.full((8, wide), 254, np.int16), v_th_mant=2**17 - 1,
                       i_decay=4096, v_decay=4096)
    probes.append(("q_wrap", "one step's input q beyond 21 bits + sign (160 inputs x 254, wgtExp 0)",
                   LoihiNetwork([q_in, q_hid], steps, metadata={"probe": True}), 0.95))
    # u lands exactly on -2**23: weights (-256, +128) both firing = -128 x 2**6 = -2**13 a step, no current
    # decay, 1024 steps (mixed signs: netx mangles an all-negative matrix holding -256, see inhibitory_with_min)
    u_in = LoihiLayer("input", "input", 2)
    u_hid = LoihiLayer("hidden", "dense", 1, weight=np.array([[-256, 128]], np.int16), v_th_mant=1, i_decay=0,
                       v_decay=4096)
    probes.append(("u_at_minus_2pow23", "u reaches exactly -2**23 (the edge of its 23 bits + sign)",
                   LoihiNetwork([u_in, u_hid], 1040, metadata={"probe": True}), 1.0))
    return probes


# -- main ------------------------------------------------------------------------------------------
def overflow_counts(snn: dict[str, np.ndarray]) -> dict[str, int]:
    """snncc's overflow counters, and how often a recorded u sat exactly on -2**23."""
    out = {k: int(snn[k]) for k in snn if k.startswith("overflow_")}
    out["u_at_minus_2pow23"] = int(sum(np.count_nonzero(snn[k] == -(2 ** 23)) for k in snn if k.endswith("_current")))
    return out


def definition_holds(res: dict[str, Any]) -> bool:
    """Whether the definition of a netx-runnable bundle predicted the measurement: no predicted
    difference <=> Lava ran it identically (spikes and state)."""
    identical = bool(res.get("all_spikes_identical") and res.get("all_state_identical")) and not res.get("lava_error")
    return identical == (not res["predicted"])


def verdict(row: Row) -> str:
    if not row.compiled:
        return "compile refused"
    r = row.result
    if r.get("lava_error"):
        return f"netx/Lava {r.get('lava_stage', '')} error"
    if r.get("all_spikes_identical") and r.get("all_state_identical"):
        return "IDENTICAL"
    if r.get("all_spikes_identical"):
        return "spikes identical, state differs"
    return "DIFFERS"


def table(rows: list[Row]) -> str:
    head = f"{'graph':32s} {'rule':9s} {'timing':6s} {'verdict':31s} {'out eq%':>8s} {'def':3s}  first diff / why"
    lines = [head, "-" * len(head)]
    for row in rows:
        r = row.result
        frac = r.get("output_equal_fraction")
        frac_s = f"{100 * frac:7.2f}%" if frac is not None else "      -"
        if not row.compiled:
            note = row.compile_error[:110]
        elif r.get("lava_error"):
            note = r["lava_error"][:110]
        else:
            fd = r.get("first_state_difference")
            note = (f"layer {fd['layer']} {fd['field']} @ step {fd['step']} n{fd['neuron']}; " if fd else "")
            note += "; ".join(r.get("predicted", []))[:160]
        if row.rule == "auto" and row.compiled:
            chosen = re.search(r"(?:chose|kept) '([^']+)'", row.chosen)   # kept: the float outputs are silent
            note = f"[auto chose {chosen.group(1) if chosen else 'global'}] " + note
        holds = {True: "ok", False: "NO"}.get(r.get("definition_holds"), "-")
        lines.append(f"{row.case:32s} {row.rule:9s} {row.timing:6s} {verdict(row):31s} {frac_s} {holds:3s}  {note}")
    return "\n".join(lines)


def first_state_difference(cmp: dict[str, Any]) -> dict[str, Any] | None:
    best = None
    for lay in cmp["layers"]:
        for field_name in ("current", "voltage", "spikes"):
            fd = lay.get(field_name, {}).get("first_difference")
            if fd and (best is None or (fd["step"], lay["layer"]) < (best["step"], best["layer"])):
                best = {"layer": lay["layer"], "field": field_name, **fd}
    return best


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--venv", default=str(DEFAULT_VENV), help="the Python 3.10 lava venv (built if missing)")
    ap.add_argument("--python310", default=None, help="Python 3.10 interpreter to build the venv with")
    ap.add_argument("--nir-dir", default=None)
    ap.add_argument("--graphs", nargs="*", default=None, help="case names (default: all)")
    ap.add_argument("--rules", nargs="*", default=list(RULES), choices=RULES)
    ap.add_argument("--timings", nargs="*", default=list(TIMINGS), choices=TIMINGS)
    ap.add_argument("--replicas", type=int, default=1, help="compile with --replicas K (lowering/replicate.py)")
    ap.add_argument("--finetune", action="store_true", help="compile with --finetune (its defaults; minutes per bundle)")
    ap.add_argument("--samples", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--quick", action="store_true", help="2 samples, the small graphs only")
    ap.add_argument("--no-probes", action="store_true")
    ap.add_argument("--work", default=None, help="keep bundles and arrays here (default: a temporary directory)")
    ap.add_argument("--timeout", type=float, default=3600.0, help="seconds for one runner process")
    ap.add_argument("--out", default=str(BENCH / "results" / "lava_netx_agreement.json"))
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    samples = 2 if args.quick else args.samples
    py = ensure_venv(Path(args.venv), find_python310(args.python310))
    versions = venv_versions(py)
    print(f"lava venv: {versions}", flush=True)
    tmp = tempfile.TemporaryDirectory(prefix="lava-netx-") if args.work is None else None
    work = Path(args.work) if args.work else Path(tmp.name)
    work.mkdir(parents=True, exist_ok=True)
    try:
        result = run(args, py, versions, work, samples)
    finally:
        if tmp is not None:
            tmp.cleanup()
    result["seconds"] = round(time.perf_counter() - t_start, 1)
    result["replicas"], result["finetuned"] = args.replicas, args.finetune
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=1, default=str) + "\n")
    print(f"\nwritten {args.out} ({result['seconds']:.0f} s)")
    return result


def run(args, py: Path, versions: dict[str, str], work: Path, samples: int) -> dict[str, Any]:
    from snncc.errors import SnnccError
    import snncc.api as api

    all_cases = [c for c in cases(nir_dir(args.nir_dir), work, args.seed)
                 if (args.graphs is None or c.name in args.graphs) and (not args.quick or c.quick)]
    rows: list[Row] = []
    by_digest: dict[str, list[Row]] = {}
    case_of: dict[str, Case] = {}
    t0 = time.perf_counter()
    for case in all_cases:
        for timing in args.timings:
            for rule in args.rules:
                row = Row(case.name, rule, timing)
                rows.append(row)
                tag = (f"__replicas{args.replicas}" if args.replicas > 1 else "") + ("__finetuned" if args.finetune else "")
                bundle = work / f"{case.name}__{rule}__{timing}{tag}.net"
                opts = dict(case.options, scale=rule, timing=timing)
                if args.replicas > 1:
                    opts["replicas"] = args.replicas
                if args.finetune:
                    opts["finetune"] = True
                if case.params is not None:
                    opts["params"] = str(case.params)
                try:
                    api.compile(str(case.path), target="loihi", output=str(bundle), **opts)
                except SnnccError as ex:
                    row.compile_error = str(ex).splitlines()[0]
                    print(f"  {case.name} {rule} {timing}: compile refused: {row.compile_error[:120]}", flush=True)
                    continue
                row.compiled, row.bundle = True, str(bundle)
                row.layer_sha256 = layer_digest(bundle)
                row.features, row.netx_compat, row.chosen = features(bundle)
                by_digest.setdefault(row.layer_sha256, []).append(row)
                case_of[row.layer_sha256] = case
                print(f"  {case.name} {rule} {timing}: compiled ({row.chosen[:90]})", flush=True)
    compile_s = time.perf_counter() - t0
    # one run per distinct bundle (rules and timings often write the same /layer contents)
    jobs, pending = [], []
    t0 = time.perf_counter()
    for digest, group in by_digest.items():
        first, case = group[0], case_of[digest]
        x = make_inputs(first, case, first.features, min(samples, case.max_samples or samples), args.seed)
        tag = digest[:16]
        snn = emulate_snncc(Path(first.bundle), x, work, tag)
        xd = drive(Path(first.bundle), x)
        np.save(work / f"{tag}_driven.npy", xd)
        out = work / f"{tag}_lava.npz"
        if out.exists():
            out.unlink()
        jobs.append({"bundle": first.bundle, "input": str(work / f"{tag}_driven.npy"), "output": str(out)})
        pending.append((digest, group, snn, out))
    emulate_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    print(f"running {len(jobs)} distinct bundles in Lava ({samples} samples each) ...", flush=True)
    failures = run_lava(py, jobs, args.timeout)
    lava_s = time.perf_counter() - t0
    for digest, group, snn, out in pending:
        if str(out) in failures:
            res = {"lava_error": failures[str(out)], "lava_stage": "runner"}
        else:
            with np.load(out, allow_pickle=False) as z:
                lava = {k: z[k] for k in z.files}
            if "error" in lava:
                res = {"lava_error": str(lava["error"]), "lava_stage": str(lava["stage"]),
                       "lava_traceback_tail": str(lava["traceback"])[-600:]}
            else:
                res = compare(snn, lava, group[0].features)
                res["first_state_difference"] = first_state_difference(res)
                res["netx_load_warnings"] = json.loads(str(lava["load_warnings"]))
        res["overflow_snncc"] = overflow_counts(snn)
        res["predicted"], res["caveats"] = predicted_differences(group[0].features, res["overflow_snncc"])
        res["definition_holds"] = definition_holds(res)
        res["samples"] = int(snn["output_spikes"].shape[0])
        res["same_bundle_as"] = [f"{r.rule}/{r.timing}" for r in group]
        for row in group:
            row.result = res
    probes = [] if args.no_probes else run_probes(py, work, args.seed, args.timeout)
    print()
    print(table(rows))
    if probes:
        print()
        print(probe_table(probes))
    judged = [r.result for r in rows if r.compiled] + [p["result"] for p in probes]
    held = sum(bool(r.get("definition_holds")) for r in judged)
    print(f"\nthe netx-runnable definition (docs/lava_netx.md) predicted {held} of {len(judged)} measured bundles "
          "(rows and probes): 'def' ok = no predicted difference <=> Lava ran it identically")
    return {
        "benchmark": "lava-dl netx 0.6 + Lava Loihi1SimCfg(fixed_pt) against snncc emulate, spike for spike",
        "synthetic_inputs": True,
        "lava_venv": versions,
        "snncc_python": platform.python_version(),
        "snncc_revision": git_revision(),
        "samples_per_bundle": samples,
        "seed": args.seed,
        "timings_s": {"compile": round(compile_s, 1), "emulate": round(emulate_s, 1), "lava": round(lava_s, 1)},
        "rows": [row_dict(r) for r in rows],
        "probes": probes,
        "load_1min": os.getloadavg()[0],
    }


def git_revision() -> str:
    """The repository's HEAD (and '+dirty' when tracked files differ), or 'unknown' outside git."""
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO, capture_output=True, text=True, check=True).stdout
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO, capture_output=True,
                               text=True, check=True).stdout
        return head.strip() + ("+dirty" if dirty.strip() else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def row_dict(row: Row) -> dict[str, Any]:
    return {"graph": row.case, "rule": row.rule, "timing": row.timing, "verdict": verdict(row),
            "compiled": row.compiled, "compile_error": row.compile_error, "chosen": row.chosen,
            "layer_sha256": row.layer_sha256, "features": row.features, "netx_compat": row.netx_compat,
            "result": row.result}


def run_probes(py: Path, work: Path, seed: int, timeout: float) -> list[dict[str, Any]]:
    from snncc.targets.loihi.bundle.write import write_bundle

    out, jobs, pending = [], [], []
    pdir = work / "probes"
    pdir.mkdir(exist_ok=True)
    for name, what, net, density in probe_networks(seed):
        bundle = pdir / f"{name}.net"
        write_bundle(net, bundle)
        facts, compat, _ = features(bundle)
        rng = np.random.default_rng([seed, len(out)])
        x = (rng.random((2, net.t_sample, net.input_width)) < density).astype(np.uint8)
        snn = emulate_snncc(bundle, x, pdir, name)
        np.save(pdir / f"{name}_driven.npy", net.drive(x))
        res_path = pdir / f"{name}_lava.npz"
        if res_path.exists():
            res_path.unlink()
        jobs.append({"bundle": str(bundle), "input": str(pdir / f"{name}_driven.npy"), "output": str(res_path)})
        pending.append((name, what, facts, compat, snn, res_path))
        out.append(None)
    print(f"running {len(jobs)} probe bundles in Lava ...", flush=True)
    failures = run_lava(py, jobs, timeout)
    results = []
    for name, what, facts, compat, snn, res_path in pending:
        if str(res_path) in failures:
            res = {"lava_error": failures[str(res_path)], "lava_stage": "runner"}
        else:
            with np.load(res_path, allow_pickle=False) as z:
                lava = {k: z[k] for k in z.files}
            if "error" in lava:
                res = {"lava_error": str(lava["error"]), "lava_stage": str(lava["stage"]),
                       "lava_traceback_tail": str(lava["traceback"])[-600:]}
            else:
                res = compare(snn, lava, facts)
                res["first_state_difference"] = first_state_difference(res)
        res["overflow_snncc"] = overflow_counts(snn)
        res["predicted"], res["caveats"] = predicted_differences(facts, res["overflow_snncc"])
        res["definition_holds"] = definition_holds(res)
        results.append({"probe": name, "feature": what, "netx_compat": compat, "result": res,
                        "verdict": verdict(Row(name, "", "", compiled=True, result=res))})
    return results


def probe_table(probes: list[dict[str, Any]]) -> str:
    head = f"{'probe':24s} {'verdict':31s} {'out eq%':>8s} {'def':3s}  first state difference / overflow (snncc)"
    lines = [head, "-" * len(head)]
    for p in probes:
        r = p["result"]
        frac = r.get("output_equal_fraction")
        frac_s = f"{100 * frac:7.2f}%" if frac is not None else "      -"
        fd = r.get("first_state_difference")
        note = r.get("lava_error", "")[:100] or (f"layer {fd['layer']} {fd['field']} @ step {fd['step']} "
                                                  f"(lava {fd['lava']}, snncc {fd['snncc']})" if fd else "")
        ov = {k.replace("overflow_", ""): v for k, v in r.get("overflow_snncc", {}).items() if v}
        holds = {True: "ok", False: "NO"}.get(r.get("definition_holds"), "-")
        lines.append(f"{p['probe']:24s} {p['verdict']:31s} {frac_s} {holds:3s}  {note} {ov if ov else ''}")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
