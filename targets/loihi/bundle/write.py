"""Writing a Loihi bundle (``layout.py`` states the layout): atomic, byte-identical for identical input.

``check_network`` applies the reader's rules (``read.py``) before anything is written, so a network
the reader would refuse is never written.
"""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.kit.writing import write_bytes_atomic
from snncc.targets.loihi import chip
from snncc.targets.loihi.bundle.layout import FORMAT_VERSION, SNNCC_GROUP
from snncc.targets.loihi.bundle.portability import PER_NEURON_NOTE
from snncc.targets.loihi.network import LoihiNetwork


def _version() -> str:
    try:
        from importlib.metadata import version

        return version("snncc")
    except Exception:  # pragma: no cover - not installed
        return "unknown"


def netx_compat(network: LoihiNetwork) -> list[str]:
    """Fields this bundle relies on that lava-dl netx ignores (so Lava would run it differently)."""
    notes = []
    k = network.layers[0].always_on
    if k:
        notes.append(f"/layer/0/alwaysOn = {k}: the last {k} input axon(s) carry current biases and must spike at "
                     "every step (snncc's emulator and runner add them; a Lava driver must too)")
    for i, lay in enumerate(network.layers[1:], start=1):
        per_neuron = [key for key, value in (("vThMant", lay.v_th_mant), ("iDecay", lay.i_decay),
                                             ("vDecay", lay.v_decay)) if np.ndim(value)]
        if per_neuron:
            notes.append(f"/layer/{i}/neuron/{{{', '.join(per_neuron)}}}: {PER_NEURON_NOTE} (compartment profiles; "
                         "Lava's LIF declares one value per layer, its CPU simulation runs the arrays as written: "
                         "measured by bench/studies/lava_netx_agreement.py, not Lava's stated interface)")
        if lay.always_on:
            notes.append(f"/layer/{i}/alwaysOn = {lay.always_on}: the last {lay.always_on} compartment(s) are bias "
                         "sources for the next layer, timed by refDelay")
        if lay.ref_delay != 1:
            notes.append(f"/layer/{i}/neuron/refDelay = {lay.ref_delay} (netx's LIF has no refractory period)")
        for key, exp in (("wgtExp", lay.wgt_exp), ("wgtExpRec", lay.wgt_exp_rec if lay.weight_rec is not None else 0)):
            if np.ndim(exp):
                used = sorted(set(np.unique(exp).tolist()))
                formats = f"{len(used)} synapse format{'s' if len(used) != 1 else ''}, one per exponent"
                notes.append(f"/layer/{i}/neuron/{key}: one exponent per synapse, {used} "
                             f"({formats}; snncc extension; netx reads no weight exponent)")
            elif exp != 0:
                notes.append(f"/layer/{i}/neuron/{key} = {exp} ("
                             + ("netx ignores weight exponents)" if key == "wgtExp" else "snncc extension)"))
        if lay.weight_rec is not None and np.any(np.asarray(lay.delay_rec) != 0):
            notes.append(f"/layer/{i}/delay_rec (snncc extension: recurrent synaptic delay)")
        if lay.bias is not None and lay.bias_exp != chip.NETX_BIAS_EXP:
            notes.append(f"/layer/{i}/neuron/biasExp = {lay.bias_exp} (netx reads bias with exponent {chip.NETX_BIAS_EXP})")
    return notes


def _string(group: h5py.Group, name: str, text: str) -> None:
    data = text.encode("utf-8")
    group.create_dataset(name, data=np.array([data], dtype=f"S{max(len(data), 1)}"), track_times=False)


def _scalar(group: h5py.Group, name: str, value, dtype) -> None:
    group.create_dataset(name, data=np.asarray(value, dtype=dtype), track_times=False)


def _array(group: h5py.Group, name: str, value, dtype) -> None:
    group.create_dataset(name, data=np.ascontiguousarray(np.asarray(value, dtype=dtype)), track_times=False)


def _json(obj: Any) -> str:
    from snncc.targets.kit.inputs import to_jsonable

    return json.dumps(to_jsonable(obj), sort_keys=True, separators=(",", ":"))


def _delay_array(delay, shape) -> np.ndarray:
    return np.ascontiguousarray(np.broadcast_to(np.asarray(delay, np.uint8), shape))


def _exponent_field(group: h5py.Group, key: str, exp) -> None:
    """A weight exponent: a scalar, or (split exponents) an int8 array shaped like the weights."""
    if np.ndim(exp):
        _array(group, key, exp, np.int8)
    else:
        _scalar(group, key, exp, np.int64)


def write_bundle(network: LoihiNetwork, path: str | Path, extra: dict[str, Any] | None = None) -> None:
    """Write ``network`` to ``path`` atomically; ``extra`` adds JSON records under /snncc."""
    check_network(network, str(path))
    # Built in memory, then written as plain bytes: HDF5 writing straight to a file crashes the
    # process (SIGSEGV) when the disk fills, where a plain write fails cleanly with ENOSPC.
    buf = io.BytesIO()
    with h5py.File(buf, "w", libver="earliest", track_order=False) as f:
        sim = f.create_group("simulation")
        _scalar(sim, "Ts", 1, np.int64)
        _scalar(sim, "tSample", network.t_sample, np.int64)
        layers = f.create_group("layer")
        for i, lay in enumerate(network.layers):
            g = layers.create_group(str(i))
            _string(g, "type", lay.kind)
            if lay.always_on:
                _scalar(g, "alwaysOn", lay.always_on, np.int64)
            if i == 0:
                _array(g, "shape", [1, 1, lay.n], np.int64)
                continue
            _array(g, "shape", [lay.n, 1, 1], np.int64)
            _array(g, "weight", lay.weight, np.int16)
            if np.any(np.asarray(lay.delay) != 0):
                _array(g, "delay", _delay_array(lay.delay, lay.weight.shape), np.uint8)
            if lay.weight_rec is not None:
                _array(g, "weight_rec", lay.weight_rec, np.int16)
                if np.any(np.asarray(lay.delay_rec) != 0):
                    _array(g, "delay_rec", _delay_array(lay.delay_rec, lay.weight_rec.shape), np.uint8)
            if lay.bias is not None:
                _array(g, "bias", lay.bias, np.int32)
            nrn = g.create_group("neuron")
            _string(nrn, "type", "LOIHI")
            for key, value in (("vThMant", lay.v_th_mant), ("iDecay", lay.i_decay), ("vDecay", lay.v_decay),
                               ("refDelay", lay.ref_delay)):
                (_array if np.ndim(value) else _scalar)(nrn, key, value, np.int64)
            _exponent_field(nrn, "wgtExp", lay.wgt_exp)
            if lay.weight_rec is not None:
                _exponent_field(nrn, "wgtExpRec", lay.wgt_exp_rec)
            if lay.bias is not None:
                _scalar(nrn, "biasExp", lay.bias_exp, np.int64)
        s = f.create_group(SNNCC_GROUP)
        _string(s, "version", _version())
        _scalar(s, "format", FORMAT_VERSION, np.int64)
        _string(s, "source_sha256", str(network.metadata.get("source_sha256", "")))
        _string(s, "metadata", _json(network.metadata))
        _string(s, "netx_compat", _json(netx_compat(network)))
        if network.core_map is not None:
            _string(s, "core_map", _json(network.core_map))
        for key, value in sorted((extra or {}).items()):
            _string(s, key, _json(value))
    write_bytes_atomic(path, buf.getvalue())


def check_network(network: LoihiNetwork, where: str = "<network>") -> None:
    """The same rules the reader enforces, applied before writing (a bad network is never written)."""
    width = network.layers[0].n
    for i, lay in enumerate(network.layers):
        if not 0 <= lay.always_on < lay.n:
            raise SnnccError("bias sources must be fewer than the layer's units", file=where, field=f"/layer/{i}/alwaysOn")
    for i, lay in enumerate(network.layers[1:], start=1):
        for key, w, shape in (("weight", lay.weight, (lay.n, width)), ("weight_rec", lay.weight_rec, (lay.n, lay.n))):
            if w is None:
                if key == "weight":
                    raise SnnccError("missing weights", file=where, field=f"/layer/{i}/{key}")
                continue
            w = np.asarray(w)
            if w.shape != shape:
                raise SnnccError(f"shape {w.shape} does not chain, expected {shape}", file=where, field=f"/layer/{i}/{key}")
            if w.size and (w.min() < chip.WEIGHT_MIN or w.max() > chip.WEIGHT_MAX or np.any(w % 2)):
                raise SnnccError(f"weights must be even integers in [{chip.WEIGHT_MIN}, {chip.WEIGHT_MAX}]", file=where,
                                 field=f"/layer/{i}/{key}")
        for key, exp, w in (("wgtExp", lay.wgt_exp, lay.weight), ("wgtExpRec", lay.wgt_exp_rec, lay.weight_rec)):
            e = np.asarray(exp)
            if (e.ndim and (w is None or e.shape != np.shape(w))) or (
                    e.size and not (chip.WGT_EXP_MIN <= e.min() and e.max() <= chip.WGT_EXP_MAX)):
                raise SnnccError(f"weight exponents must lie in {chip.WGT_EXP_MIN}..{chip.WGT_EXP_MAX}, one per layer or "
                                 "one per synapse", file=where, field=f"/layer/{i}/neuron/{key}")
        for key, delay in (("delay", lay.delay), ("delay_rec", lay.delay_rec if lay.weight_rec is not None else 0)):
            d = np.asarray(delay)
            if d.size and (d.min() < 0 or d.max() > chip.MAX_EXTRA_DELAY):
                raise SnnccError(f"delays must be integers in 0..{chip.MAX_EXTRA_DELAY}", file=where,
                                 field=f"/layer/{i}/{key}")
        for key, attr in (("iDecay", "i_decay"), ("vDecay", "v_decay"), ("vThMant", "v_th_mant")):
            value = np.asarray(getattr(lay, attr))
            if value.ndim and value.shape != (lay.n,):
                raise SnnccError(f"per-neuron registers need one value per neuron ({lay.n})", file=where,
                                 field=f"/layer/{i}/neuron/{key}")
        for key in ("i_decay", "v_decay"):
            if not (0 <= np.min(getattr(lay, key)) and np.max(getattr(lay, key)) <= chip.DECAY_ONE):
                raise SnnccError(f"decays must lie in 0..{chip.DECAY_ONE}", file=where, field=f"/layer/{i}/neuron/{key}")
        if not (chip.V_TH_MANT_MIN <= np.min(lay.v_th_mant) and np.max(lay.v_th_mant) <= chip.V_TH_MANT_MAX):
            raise SnnccError(f"vThMant must lie in {chip.V_TH_MANT_MIN}..{chip.V_TH_MANT_MAX}", file=where,
                             field=f"/layer/{i}/neuron/vThMant")
        if not chip.REF_DELAY_MIN <= lay.ref_delay <= chip.REF_DELAY_MAX:
            raise SnnccError(f"refDelay must lie in {chip.REF_DELAY_MIN}..{chip.REF_DELAY_MAX}", file=where,
                             field=f"/layer/{i}/neuron/refDelay")
        if lay.bias is not None and (np.any(np.abs(np.asarray(lay.bias)) > chip.BIAS_MANT_MAX)
                                     or not 0 <= lay.bias_exp <= chip.BIAS_EXP_STORED_MAX):
            raise SnnccError(f"bias mantissas must fit 13 bits signed (|b| <= {chip.BIAS_MANT_MAX}), biasExp "
                             f"0..{chip.BIAS_EXP_STORED_MAX}", file=where, field=f"/layer/{i}/bias")
        width = lay.n
