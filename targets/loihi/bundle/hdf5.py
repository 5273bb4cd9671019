"""Loihi bundles: HDF5 in the lava-dl netx layout (which SLAYER v1 also wrote), plus snncc's own groups.

    /simulation/Ts = 1, /simulation/tSample = T
    /layer/0/{type="input", shape=[1, 1, C]}
    /layer/i/{type="dense"|"dense_rec", shape=[n, 1, 1], weight (out, in), weight_rec (n, n),
              delay (out, in), bias, neuron/{type="LOIHI", vThMant, iDecay, vDecay, refDelay, wgtExp}}
    snncc extensions (netx ignores them): /layer/i/delay_rec, neuron/{wgtExpRec, biasExp},
    /layer/i/alwaysOn (the layer's last k units are bias sources: input axons held at 1 every step,
    or compartments that fire on their own; see lowering/bias_sources.py)
    /snncc/{version, quantization, timing, validation, metadata (JSON strings), source_sha256,
            core_map (JSON, when mapped), netx_compat (what netx would run differently),
            portability (JSON: netx_runnable, line, reasons, best_netx_rule; bundle/portability.py),
            liveness (JSON: every population's activity on the calibration inputs, float and Loihi)}
    metadata holds compile_options (timing, scale, allow_reset_change, time_steps: what check re-lowers
    with), input_copies / base_inputs (the data's channels, tiled by snncc) and input_shape (C, H, W)

The writer is atomic and byte-identical for identical input (no timestamps, fixed order). The
reader also accepts SLAYER v1 files as the paper's authors wrote them (a ``flatten`` layer after
the input, type ``recurrent`` with ``recWeight``, float-typed even weights, ``neuron/theta`` =
vThMant * 2**6 when vThMant is absent, ``tauRho``/``scaleRho`` ignored) and validates everything
it reads: one SnnccError line naming the file, the HDF5 path and the rule. The ranges it checks
are ``chip.py``'s, read at call time (the reader and ``check_network``, which the writer runs, agree).
"""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from snncc.atomic import write_bytes_atomic
from snncc.errors import SnnccError
from snncc.hdf5_links import check_self_contained
from snncc.limits import check_memory, check_time_steps
from snncc.targets.loihi import chip
from snncc.targets.loihi.bundle.portability import PER_NEURON_NOTE
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork

SNNCC_GROUP = "snncc"
MAX_TEXT_BYTES = 64 * 2**20    # a text field (type, JSON record) of a bundle: one string of at most 64 MiB
FORMAT_VERSION = 1


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
                         "measured by bench/lava_netx_agreement.py, not Lava's stated interface)")
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
    from snncc.records import to_jsonable

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


# -- reading ---------------------------------------------------------------------------------------
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
    w = np.asarray(ds[()], np.float64)
    if not np.all(np.isfinite(w)):
        _fail(path, f"{where}/{key}", "contains NaN or Inf")
    if np.any(w != np.round(w)) or np.any(np.round(w) % 2 != 0):
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
        from snncc.artefact_paths import LOIHI_BUNDLE, wrong_path

        raise wrong_path(path, LOIHI_BUNDLE)
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
        for key in ("metadata", "quantization", "timing", "validation", "netx_compat", "core_map", "portability",
                    "liveness"):
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
        names = meta.get("layer_names")
        if isinstance(names, list) and len(names) == len(layers):
            for lay, name in zip(layers, names):
                lay.name = str(name)
    return LoihiNetwork(layers=layers, t_sample=int(t_sample), metadata=meta, core_map=core_map)


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
