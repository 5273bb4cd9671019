"""Reading a Loihi bundle (``layout.py`` states the layout), written by snncc, lava-dl netx or SLAYER v1.

Everything read is validated first: one SnnccError line naming the file, the HDF5 path and the rule.
A dataset is refused by its declared size before it is read; a link that leads to another file is
refused before any value is read (``kit.hdf5``).
"""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.kit.compute import check_memory, check_time_steps
from snncc.targets.loihi import chip
from snncc.targets.loihi.bundle.layout import KIND, MAX_TEXT_BYTES, RECORDS, SNNCC_GROUP
from snncc.targets.kit.hdf5 import check_self_contained
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork


def not_a_bundle(path: str | Path) -> SnnccError:
    """The refusal of a path that is no regular file: missing, a directory, or something else."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return SnnccError("file does not exist", file=str(path), field="path")
    if stat.S_ISDIR(mode):
        return SnnccError(f"is a directory, not {KIND}", file=str(path), field="path")
    return SnnccError(f"is not a regular file (a device or pipe), not {KIND}", file=str(path), field="path")


def _fail(path: str, field: str, rule: str) -> None:
    raise SnnccError(rule, file=path, field=field)


def _declared(ds: Any, path: str, field: str, max_elements: int | None = None) -> None:
    """Refuse a dataset by its DECLARED size, before reading it (a small file can declare a huge
    dataset that was never written): at most ``max_elements`` values and what fits in memory."""
    if not isinstance(ds, h5py.Dataset):
        return
    if max_elements is not None and ds.size > max_elements:
        _fail(path, field, f"declares {ds.size:,} values (shape {ds.shape}); at most {max_elements:,} belong here")
    check_memory(int(ds.size) * max(int(ds.dtype.itemsize), 8), f"the declared dataset (shape {ds.shape})",
                 file=path, field=field)


def _text(ds: Any) -> str:
    if isinstance(ds, h5py.Dataset):
        _declared(ds, None, ds.name or "string", max_elements=1)
        if ds.size * ds.dtype.itemsize > MAX_TEXT_BYTES:
            _fail(None, ds.name or "string", f"declares a {ds.dtype.itemsize:,}-byte string; text fields hold at most "
                  f"{MAX_TEXT_BYTES:,} bytes")
    value = ds[()] if isinstance(ds, h5py.Dataset) else ds
    if isinstance(value, np.ndarray):
        value = value.reshape(-1)[0] if value.size else b""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace").strip("\x00").strip()
    return str(value).strip()


def _get(group: h5py.Group, key: str, path: str, where: str) -> Any:
    if key not in group:
        _fail(path, f"{where}/{key}", "missing (required field)")
    return group[key]


def _number(group: h5py.Group, key: str, path: str, where: str, default=None, integer: bool = True):
    if key not in group:
        if default is None:
            _fail(path, f"{where}/{key}", "missing (required field)")
        return default
    ds = group[key]
    if not isinstance(ds, h5py.Dataset) or ds.dtype.kind not in "biuf":
        _fail(path, f"{where}/{key}", "must be a numeric dataset")
    if ds.size != 1:
        _fail(path, f"{where}/{key}", f"must hold one value, holds {ds.size}")
    arr = np.asarray(ds[()]).reshape(-1)
    if arr.size != 1:
        _fail(path, f"{where}/{key}", f"must hold one value, holds {arr.size}")
    value = arr[0]
    if not np.isfinite(value):
        _fail(path, f"{where}/{key}", "must be finite")
    if integer:
        if value != np.round(value):
            _fail(path, f"{where}/{key}", f"must be an integer, got {value}")
        return int(value)
    return float(value)


def _weights(group: h5py.Group, key: str, path: str, where: str, shape: tuple[int, int]) -> np.ndarray:
    ds = _get(group, key, path, where)
    if not isinstance(ds, h5py.Dataset) or ds.dtype.kind not in "iuf":
        _fail(path, f"{where}/{key}", f"must be a numeric array, got {getattr(ds, 'dtype', type(ds).__name__)}")
    if ds.shape != shape:
        _fail(path, f"{where}/{key}", f"shape {ds.shape} does not chain: expected {shape} (out, in)")
    _declared(ds, path, f"{where}/{key}")
    raw = ds[()]
    if np.asarray(raw).dtype.kind in "iu":          # as snncc writes them (int16): checked as integers, one pass each
        w = np.asarray(raw)
        if np.any(w & 1):
            _fail(path, f"{where}/{key}", "weights must be even integers (8-bit mantissas, step 2)")
        lo, hi = (int(w.min()), int(w.max())) if w.size else (0, 0)
        if lo < chip.WEIGHT_MIN or hi > chip.WEIGHT_MAX:
            _fail(path, f"{where}/{key}", f"weights must lie in [{chip.WEIGHT_MIN}, {chip.WEIGHT_MAX}], "
                  f"found [{lo:g}, {hi:g}]")
        return w.astype(np.int16, copy=w.dtype != np.int16)
    w = np.asarray(raw, np.float64)                 # float-typed even weights (SLAYER v1)
    if not np.all(np.isfinite(w)):
        _fail(path, f"{where}/{key}", "contains NaN or Inf")
    r = np.round(w)
    if np.any(w != r) or np.any(r % 2 != 0):
        _fail(path, f"{where}/{key}", "weights must be even integers (8-bit mantissas, step 2)")
    if w.size and (w.min() < chip.WEIGHT_MIN or w.max() > chip.WEIGHT_MAX):
        _fail(path, f"{where}/{key}", f"weights must lie in [{chip.WEIGHT_MIN}, {chip.WEIGHT_MAX}], "
              f"found [{w.min():g}, {w.max():g}]")
    return w.astype(np.int16)


def _delays(group: h5py.Group, key: str, path: str, where: str, shape: tuple[int, int]):
    if key not in group:
        return 0
    ds = group[key]
    if not isinstance(ds, h5py.Dataset) or ds.dtype.kind not in "iuf":
        _fail(path, f"{where}/{key}", "must be a numeric array")
    if ds.size not in (1, shape[0], shape[0] * shape[1]):
        _fail(path, f"{where}/{key}", f"declares shape {ds.shape}: delays need 1 value, one per neuron ({shape[0]}) "
              f"or one per synapse {shape}")
    _declared(ds, path, f"{where}/{key}")
    d = np.asarray(ds[()], np.float64)
    if d.ndim == 1 and d.shape[0] == shape[0]:
        d = np.repeat(d[:, None], shape[1], axis=1)
    elif d.size == 1:
        d = np.full(shape, float(d.reshape(-1)[0]))
    if d.shape != shape:
        _fail(path, f"{where}/{key}", f"shape {d.shape} matches neither the weights {shape} nor the neurons")
    if (not np.all(np.isfinite(d)) or np.any(d != np.round(d)) or d.min(initial=0) < 0
            or d.max(initial=0) > chip.MAX_EXTRA_DELAY):
        _fail(path, f"{where}/{key}", f"delays must be integers in 0..{chip.MAX_EXTRA_DELAY}")
    d = d.astype(np.int64)
    return int(d.flat[0]) if d.size and np.all(d == d.flat[0]) else d


def _shape_width(group: h5py.Group, path: str, where: str) -> int:
    ds = _get(group, "shape", path, where)
    if not isinstance(ds, h5py.Dataset) or ds.dtype.kind not in "iuf":
        _fail(path, f"{where}/shape", "must be a numeric array")
    _declared(ds, path, f"{where}/shape", max_elements=8)
    shape = np.asarray(ds[()]).reshape(-1)
    if shape.size == 0 or np.any(shape < 1) or np.any(shape != np.round(shape)):
        _fail(path, f"{where}/shape", "must be positive integers")
    return int(np.prod(shape))


def _register(group: h5py.Group, key: str, path: str, where: str, n: int):
    """A compartment register: one integer, or (a profile per neuron) an integer array of n values."""
    if key in group and isinstance(group[key], h5py.Dataset) and group[key].size > 1:
        ds = group[key]
        if ds.dtype.kind not in "iuf" or ds.shape != (n,):
            _fail(path, f"{where}/{key}", f"per-neuron values must be a numeric array of {n}")
        value = np.asarray(ds[()], np.float64)
        if not np.all(np.isfinite(value)) or np.any(value != np.round(value)):
            _fail(path, f"{where}/{key}", "must be integers")
        return value.astype(np.int64)
    return _number(group, key, path, where)


def _exponents(group: h5py.Group, key: str, path: str, where: str, shape: tuple, default):
    """A weight exponent in -6..7 (chip.WGT_EXP_*): one value, or one per synapse (an array shaped like the weights)."""
    if key in group and isinstance(group[key], h5py.Dataset) and group[key].size > 1:
        ds = group[key]
        if ds.dtype.kind not in "iu" or ds.shape != tuple(shape):
            _fail(path, f"{where}/{key}", f"per-synapse exponents must be an integer array shaped {tuple(shape)}")
        value = np.asarray(ds[()], np.int64)
        low, high = int(value.min()), int(value.max())
    else:
        if default is None and key not in group:
            _fail(path, f"{where}/{key}", "missing (required with per-synapse feed-forward exponents)")
        value = low = high = _number(group, key, path, where, default=default)
    if not (chip.WGT_EXP_MIN <= low and high <= chip.WGT_EXP_MAX):
        _fail(path, f"{where}/{key}", f"must lie in {chip.WGT_EXP_MIN}..{chip.WGT_EXP_MAX} (integer chip weights), "
              f"got {low}..{high}")
    return value


def _always_on(group: h5py.Group, path: str, where: str, n: int) -> int:
    k = _number(group, "alwaysOn", path, where, default=0)
    if not 0 <= k < n:
        _fail(path, f"{where}/alwaysOn", f"must lie in 0..{n - 1} (bias sources at the end of a layer of {n})")
    return k


def _check_layer_size(path: str, where: str, n: int, width: int, rec: bool) -> None:
    """A layer's declared size must fit this machine's memory (the reader holds its weights as float64);
    the message also says how many Loihi 1 chips such a layer would take (chip.py's core limits)."""
    per_chip = chip.CORES_PER_CHIP * chip.COMPARTMENTS_PER_CORE
    n_weights = n * width + (n * n if rec else 0)
    chips = -(-n // per_chip)
    context = (f"{n:,} neurons x {width:,} inputs (as compartments alone, {chips:,} Loihi 1 chip(s) of "
               f"{chip.CORES_PER_CHIP} cores x {chip.COMPARTMENTS_PER_CORE} compartments)")
    check_memory(8 * n_weights, f"the declared layer of {context}", file=path, field=f"{where}/weight")


def read_bundle(path: str | Path) -> LoihiNetwork:
    """Read and validate a bundle written by snncc, lava-dl netx or SLAYER v1."""
    path = str(path)
    if not Path(path).is_file():
        raise not_a_bundle(path)
    try:
        f = h5py.File(path, "r")
    except (OSError, RuntimeError, ValueError):
        _fail(path, "format", "not an HDF5 file (a Loihi bundle is HDF5)")
    with f:
        try:
            check_self_contained(f, path)   # before any value is read: no link may lead to another file
            return _read(f, path)
        except SnnccError as err:
            raise err.with_file(path) from None
        except (KeyError, ValueError, TypeError, OSError, RuntimeError, AttributeError, IndexError) as ex:
            _fail(path, "format", f"unreadable bundle ({type(ex).__name__}: {str(ex).splitlines()[0] if str(ex) else ''})")
    raise AssertionError("unreachable")  # pragma: no cover


def _read(f: h5py.File, path: str) -> LoihiNetwork:
    if "layer" not in f or not isinstance(f["layer"], h5py.Group):
        _fail(path, "/layer", "missing group (a Loihi bundle lists its layers under /layer)")
    if "simulation" not in f or not isinstance(f["simulation"], h5py.Group):
        _fail(path, "/simulation", "missing group (needs /simulation/tSample)")
    t_sample = _number(f["simulation"], "tSample", path, "/simulation")
    if t_sample < 1:
        _fail(path, "/simulation/tSample", "must be >= 1")
    check_time_steps(t_sample, f"tSample = {t_sample}", file=path, field="/simulation/tSample")
    group = f["layer"]
    keys = list(group.keys())
    if not all(k.isdigit() for k in keys) or sorted(int(k) for k in keys) != list(range(len(keys))):
        _fail(path, "/layer", f"layers must be numbered 0..n-1, found {sorted(keys)}")
    if len(keys) < 2:
        _fail(path, "/layer", "needs an input layer and at least one neuron layer")
    layers: list[LoihiLayer] = []
    hdf5_index: list[int] = []     # HDF5 layer index of each network layer (a flatten layer has none)
    width = None
    dialect = "snncc" if SNNCC_GROUP in f else "netx"
    for i in range(len(keys)):
        where = f"/layer/{i}"
        g = group[str(i)]
        if not isinstance(g, h5py.Group):
            _fail(path, where, "must be a group")
        kind = _text(_get(g, "type", path, where)).lower()
        if i == 0:
            if kind != "input":
                _fail(path, f"{where}/type", f"layer 0 must be the input, got {kind!r}")
            width = _shape_width(g, path, where)
            layers.append(LoihiLayer(name="input", kind="input", n=width, always_on=_always_on(g, path, where, width)))
            hdf5_index.append(0)
            continue
        if kind == "flatten":
            dialect = "slayer-v1"
            if "shape" in g and _shape_width(g, path, where) != width:
                _fail(path, f"{where}/shape", "a flatten layer must keep the width")
            continue
        if kind not in ("dense", "dense_rec", "recurrent"):
            _fail(path, f"{where}/type", f"unsupported layer type {kind!r} (dense, dense_rec, recurrent, flatten)")
        w = _get(g, "weight", path, where)
        if not isinstance(w, h5py.Dataset) or w.dtype.kind not in "iuf":
            _fail(path, f"{where}/weight", f"must be a numeric array, got {getattr(w, 'dtype', type(w).__name__)}")
        if w.ndim != 2:
            _fail(path, f"{where}/weight", "must be a 2-D (out, in) array")
        n = int(w.shape[0])
        _check_layer_size(path, where, n, width, rec=kind != "dense")
        if "shape" in g and _shape_width(g, path, where) != n:
            _fail(path, f"{where}/shape", f"says {_shape_width(g, path, where)} neurons, weight has {n} rows")
        lay = LoihiLayer(name=f"layer{i}", kind="dense_rec" if kind != "dense" else "dense", n=n,
                         always_on=_always_on(g, path, where, n))
        lay.weight = _weights(g, "weight", path, where, (n, width))
        lay.delay = _delays(g, "delay", path, where, (n, width))
        if kind != "dense":
            rec_key = "weight_rec" if kind == "dense_rec" else "recWeight"
            if kind == "recurrent":
                dialect = "slayer-v1"
            lay.weight_rec = _weights(g, rec_key, path, where, (n, n))
            lay.delay_rec = _delays(g, "delay_rec", path, where, (n, n))
        if "neuron" not in g or not isinstance(g["neuron"], h5py.Group):
            _fail(path, f"{where}/neuron", "missing group")
        nrn = g["neuron"]
        nw = f"{where}/neuron"
        if "vThMant" in nrn:
            lay.v_th_mant = _register(nrn, "vThMant", path, nw, n)
        elif "theta" in nrn:
            theta = _number(nrn, "theta", path, nw, integer=False)
            unit = 1 << chip.V_TH_SHIFT
            if theta <= 0 or theta % unit:
                _fail(path, f"{nw}/theta", f"SLAYER's theta is the on-chip threshold vThMant * 2**{chip.V_TH_SHIFT}: "
                      f"a positive multiple of {unit}")
            lay.v_th_mant = int(theta) >> chip.V_TH_SHIFT
        else:
            _fail(path, f"{nw}/vThMant", "missing (required field)")
        if not (chip.V_TH_MANT_MIN <= np.min(lay.v_th_mant) and np.max(lay.v_th_mant) <= chip.V_TH_MANT_MAX):
            _fail(path, f"{nw}/vThMant", f"must lie in {chip.V_TH_MANT_MIN}..{chip.V_TH_MANT_MAX}, "
                  f"got {np.min(lay.v_th_mant)}..{np.max(lay.v_th_mant)}")
        for key, attr in (("iDecay", "i_decay"), ("vDecay", "v_decay")):
            value = _register(nrn, key, path, nw, n)
            if not (0 <= np.min(value) and np.max(value) <= chip.DECAY_ONE):
                _fail(path, f"{nw}/{key}", f"decays must lie in 0..{chip.DECAY_ONE}, got {np.min(value)}..{np.max(value)}")
            setattr(lay, attr, value)
        lay.ref_delay = _number(nrn, "refDelay", path, nw, default=chip.REF_DELAY_MIN)
        if not chip.REF_DELAY_MIN <= lay.ref_delay <= chip.REF_DELAY_MAX:
            _fail(path, f"{nw}/refDelay", f"must lie in {chip.REF_DELAY_MIN}..{chip.REF_DELAY_MAX}, got {lay.ref_delay}")
        lay.wgt_exp = _exponents(nrn, "wgtExp", path, nw, lay.weight.shape, default=0)
        if lay.weight_rec is not None:  # SLAYER's recurrent layers share one exponent
            lay.wgt_exp_rec = _exponents(nrn, "wgtExpRec", path, nw, lay.weight_rec.shape,
                                         default=lay.wgt_exp if np.ndim(lay.wgt_exp) == 0 else None)
        if "bias" in g:
            b = g["bias"]
            if not isinstance(b, h5py.Dataset) or b.dtype.kind not in "iuf":
                _fail(path, f"{where}/bias", "must be a numeric array")
            if b.size not in (1, n):
                _fail(path, f"{where}/bias", f"declares {b.size:,} values; a layer of {n} needs 1 or {n}")
            bias = np.asarray(b[()], np.float64).reshape(-1)
            if bias.size == 1:
                bias = np.full(n, bias[0])
            if bias.shape != (n,) or not np.all(np.isfinite(bias)) or np.any(bias != np.round(bias)):
                _fail(path, f"{where}/bias", f"must be {n} integer mantissas")
            if np.any(np.abs(bias) > chip.BIAS_MANT_MAX):
                _fail(path, f"{where}/bias", f"bias mantissas must fit 13 bits signed (|b| <= {chip.BIAS_MANT_MAX})")
            lay.bias = bias.astype(np.int64)
            lay.bias_exp = _number(nrn, "biasExp", path, nw, default=chip.NETX_BIAS_EXP)
            if not 0 <= lay.bias_exp <= chip.BIAS_EXP_STORED_MAX:
                _fail(path, f"{nw}/biasExp", f"must lie in 0..{chip.BIAS_EXP_STORED_MAX}")
        layers.append(lay)
        hdf5_index.append(i)
        width = n
    meta: dict[str, Any] = {"dialect": dialect, "hdf5_layer_index": hdf5_index}
    core_map = None
    if SNNCC_GROUP in f:
        s = f[SNNCC_GROUP]
        for key in RECORDS:
            if key in s:
                try:
                    value = json.loads(_text(s[key]))
                except json.JSONDecodeError:
                    _fail(path, f"/snncc/{key}", "must be a JSON string")
                if key == "core_map":
                    core_map = value
                elif key == "metadata":
                    meta.update(value)
                else:
                    meta[key] = value
        if "source_sha256" in s:
            meta["source_sha256"] = _text(s["source_sha256"])
        shift = meta.get("output_shift", 0)
        if not isinstance(shift, int) or isinstance(shift, bool) or not 0 <= shift < t_sample:
            _fail(path, "/snncc/metadata", f"output_shift must be an integer in 0..{t_sample - 1}, got {shift!r}")
        check_metadata(meta, layers, int(t_sample), path)
        names = meta.get("layer_names")
        if isinstance(names, list) and len(names) == len(layers):
            for lay, name in zip(layers, names):
                lay.name = str(name)
    return LoihiNetwork(layers=layers, t_sample=int(t_sample), metadata=meta, core_map=core_map)


def _whole(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def check_metadata(meta: dict[str, Any], layers: list[LoihiLayer], t_sample: int, path: str) -> None:
    """What snncc's own records say of the network must match the layers the file holds (an edited or damaged
    bundle is refused in one line, naming ``/snncc/metadata`` and the field, before anything runs):

        layer_names            one name (text) per layer under /layer
        relayed_layer_index    increasing layer indices, starting at 0, within the layers
        population_shifts      population -> steps in 0..tSample-1
        replication            replicas 1..16, the relay layer's name, and per population [model size, size], the
                               size its layer holds, the model size K-fold or 1-fold
        compile_options        a mapping
    """
    from snncc.targets.loihi.options import MAX_REPLICAS

    where = "/snncc/metadata"

    def refuse(rule: str) -> None:
        _fail(path, where, rule)

    names = meta.get("layer_names")
    if names is not None:
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            refuse("layer_names must be a list of layer names")
        if len(names) != len(layers):
            refuse(f"layer_names lists {len(names)} layers but /layer holds {len(layers)} (a layer was removed or "
                   "added after compile)")
    index = meta.get("relayed_layer_index")
    if index is not None:
        if (not isinstance(index, list) or not index or not all(_whole(i) for i in index) or index[0] != 0
                or any(b <= a for a, b in zip(index, index[1:])) or index[-1] >= len(layers)):
            refuse(f"relayed_layer_index must be increasing layer indices from 0 below {len(layers)}")
    shifts = meta.get("population_shifts")
    if shifts is not None and (not isinstance(shifts, dict) or not all(
            isinstance(k, str) and _whole(v) and 0 <= v < t_sample for k, v in shifts.items())):
        refuse(f"population_shifts must map population names to steps in 0..{t_sample - 1}")
    options = meta.get("compile_options")
    if options is not None and not isinstance(options, dict):
        refuse("compile_options must be a mapping of option names to values")
    record = meta.get("replication")
    if record is None:
        return
    if not isinstance(record, dict):
        refuse("replication must be a record (replicas, relay, populations), as compile --replicas writes it")
    k = record.get("replicas")
    if not _whole(k) or not 1 <= k <= MAX_REPLICAS:
        refuse(f"replication replicas must be a whole number from 1 to {MAX_REPLICAS}")
    by_name = {lay.name: lay for lay in layers} if names is None else dict(zip(names, layers))
    if not isinstance(record.get("relay"), str) or record["relay"] not in by_name:
        refuse("replication relay must name one of the bundle's layers")
    populations = record.get("populations")
    if not isinstance(populations, dict) or not populations:
        refuse("replication populations must map each copied population to [model size, size]")
    for name, sizes in populations.items():
        ok = (isinstance(sizes, list) and len(sizes) == 2 and all(_whole(n) and n >= 1 for n in sizes)
              and sizes[1] in (sizes[0], sizes[0] * k))
        if not ok:
            refuse(f"replication populations: {name!r} must map to [model size, size], the size the model size once "
                   f"or {k} times")
        lay = by_name.get(name)
        if lay is None or lay.model_n != sizes[1]:
            refuse(f"replication populations: {name!r} must name a layer of {sizes[1]} neurons"
                   + ("" if lay is None else f" (its layer holds {lay.model_n})"))
