"""``XyloSpec``: a Xylo network as the keyword arguments of Rockpool's ``XyloSim.from_specification``.

Fields, named exactly as those keyword arguments (N hidden neurons, Nin inputs, Nout outputs;
N_ien <= N hidden neurons take input weights: the first ones; N_oen <= N give output weights:
the LAST ones, neuron N - N_oen + i owning row i of ``weights_out``):

    weights_in   int8  (Nin, N_ien) or (Nin, N_ien, S)     S synapses used (1 or 2; 2-D: synapse 0 only)
    weights_rec  int8  (N, N) or (N, N, S)
    weights_out  int8  (N_oen, Nout)
    dash_mem, dash_syn, dash_syn_2            uint8 (N,)     bit-shift decays, 0 .. 15
    dash_mem_out, dash_syn_out                uint8 (Nout,)
    threshold int16 (N,)   threshold_out int16 (Nout,)   bias int16 (N,)   bias_out int16 (Nout,)
    weight_shift_in, weight_shift_rec, weight_shift_out   int, 0 .. 15: w_eff = int16(w << shift)
    aliases      N lists of hidden-neuron indices (a neuron's spikes are copied to its targets)
    dt           float, seconds per step

The record checks its own consistency (shapes, integer types, the core's ranges from
``chip.CORE``) when built; ``check_chip`` checks one chip's limits (sizes, expansion neurons,
synapses, fan-out, aliases). Every refusal is one ``SnnccError`` line naming the field, the rule
and the numbers. ``save_npz`` writes it atomically as arrays only (``aliases`` as an int32
(N, A) array padded with -1, ``dt`` and the shifts as 0-d arrays); ``load_npz`` reads it with
``np.load(allow_pickle=False)``, refusing a missing, extra or malformed member in one line.
``kwargs()`` gives the exact keyword arguments for ``from_specification``.
"""

from __future__ import annotations

import math
import zipfile
import zlib
from dataclasses import dataclass, fields

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.xylo.chip import CORE, XyloChip, get_chip

WEIGHT_FIELDS = ("weights_in", "weights_rec", "weights_out")
HIDDEN_FIELDS = ("dash_mem", "dash_syn", "dash_syn_2", "threshold", "bias")
OUTPUT_FIELDS = ("dash_mem_out", "dash_syn_out", "threshold_out", "bias_out")
SHIFT_FIELDS = ("weight_shift_in", "weight_shift_rec", "weight_shift_out")
NPZ_KEYS = WEIGHT_FIELDS + HIDDEN_FIELDS + OUTPUT_FIELDS + SHIFT_FIELDS + ("aliases", "dt")

# dtype of each field in the record and in spec.npz, and the range its values must lie in
_DASH = (np.uint8, 0, CORE.dash_max)
_WEIGHT = (np.int8, CORE.weight_min, CORE.weight_max)
_THRESHOLD = (np.int16, CORE.threshold_min, CORE.threshold_max)
_BIAS = (np.int16, CORE.bias_min, CORE.bias_max)
_SHIFT = (np.int8, CORE.weight_shift_min, CORE.weight_shift_max)
FIELD_TYPES = {
    "weights_in": _WEIGHT, "weights_rec": _WEIGHT, "weights_out": _WEIGHT,
    "dash_mem": _DASH, "dash_syn": _DASH, "dash_syn_2": _DASH, "dash_mem_out": _DASH, "dash_syn_out": _DASH,
    "threshold": _THRESHOLD, "threshold_out": _THRESHOLD, "bias": _BIAS, "bias_out": _BIAS,
    "weight_shift_in": _SHIFT, "weight_shift_rec": _SHIFT, "weight_shift_out": _SHIFT,
}
ALIAS_DTYPE = np.int32
DT_DTYPE = np.float64
MAX_ALIASES_STORED = 64      # alias targets per neuron an npz may declare (the chips allow 1)


def _integers(name: str, value, shape: tuple[int, ...] | None = None, ndims: tuple[int, ...] = ()) -> np.ndarray:
    """``value`` as a read-only array of the field's dtype after checking integer type, shape and range."""
    dtype, lo, hi = FIELD_TYPES[name]
    a = np.asarray(value)
    if ndims and a.ndim not in ndims:
        raise SnnccError(f"must have {' or '.join(f'{d} axes' for d in ndims)}, got shape {a.shape}", field=name)
    if shape is not None and a.shape != shape:
        raise SnnccError(f"must have shape {shape}, got {a.shape}", field=name)
    if a.dtype.kind not in "iu":
        raise SnnccError(f"must hold integers, got dtype {a.dtype} (round explicitly before building a spec)",
                         field=name)
    if a.size and (int(a.min()) < lo or int(a.max()) > hi):
        bad = int(a.min()) if int(a.min()) < lo else int(a.max())
        raise SnnccError(f"values must lie in [{lo}, {hi}], found {bad}", field=name)
    out = np.array(a, dtype=dtype)
    out.setflags(write=False)
    return out


def _shift(name: str, value) -> int:
    _, lo, hi = FIELD_TYPES[name]
    a = np.asarray(value)
    if a.ndim != 0 or a.dtype.kind not in "iu":
        raise SnnccError(f"must be one integer, got {value!r}", field=name)
    v = int(a)
    if not lo <= v <= hi:
        raise SnnccError(f"must lie in [{lo}, {hi}], got {v}", field=name)
    return v


def _dt(value) -> float:
    a = np.asarray(value)
    if a.ndim != 0 or a.dtype.kind not in "iuf":
        raise SnnccError(f"must be one real number (seconds), got {value!r}", field="dt")
    v = float(a)
    if not (math.isfinite(v) and v > 0):
        raise SnnccError(f"must be a finite number of seconds > 0, got {v}", field="dt")
    return v


def _aliases(value, n_hidden: int) -> tuple[tuple[int, ...], ...]:
    """N lists of targets (or an (N, A) integer array padded with trailing -1) -> tuple of tuples."""
    if isinstance(value, np.ndarray):
        if value.ndim != 2 or value.shape[0] != n_hidden or value.dtype.kind not in "iu":
            raise SnnccError(f"must be an integer array (N = {n_hidden}, A) padded with -1, got {value.dtype} "
                             f"{value.shape}", field="aliases")
        rows = []
        for i, row in enumerate(value.tolist()):
            kept = [t for t in row if t != -1]
            if row[:len(kept)] != kept:
                raise SnnccError(f"row {i} has a -1 before a target; padding must be trailing", field="aliases")
            rows.append(kept)
        value = rows
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != n_hidden:
        raise SnnccError(f"must hold one list of alias targets per hidden neuron (N = {n_hidden})", field="aliases")
    out = []
    for i, targets in enumerate(value):
        if isinstance(targets, (str, bytes)) or not hasattr(targets, "__iter__"):
            raise SnnccError(f"entry {i} must be a list of hidden-neuron indices, got {targets!r}", field="aliases")
        row = []
        for t in targets:
            a = np.asarray(t)
            if a.ndim != 0 or a.dtype.kind not in "iu" or not 0 <= int(a) < n_hidden:
                raise SnnccError(f"neuron {i}: target {t!r} is not a hidden-neuron index in [0, {n_hidden - 1}]",
                                 field="aliases")
            row.append(int(a))
        out.append(tuple(row))
    return tuple(out)


@dataclass(frozen=True, eq=False)
class XyloSpec:
    """A Xylo network, one field per keyword argument of ``XyloSim.from_specification``."""

    weights_in: np.ndarray
    weights_rec: np.ndarray
    weights_out: np.ndarray
    dash_mem: np.ndarray
    dash_syn: np.ndarray
    dash_syn_2: np.ndarray
    dash_mem_out: np.ndarray
    dash_syn_out: np.ndarray
    threshold: np.ndarray
    threshold_out: np.ndarray
    bias: np.ndarray
    bias_out: np.ndarray
    weight_shift_in: int
    weight_shift_rec: int
    weight_shift_out: int
    aliases: tuple
    dt: float

    def __post_init__(self):
        def put(name, value):
            object.__setattr__(self, name, value)

        w_rec = _integers("weights_rec", self.weights_rec, ndims=(2, 3))
        n = w_rec.shape[0]
        if n < 1 or w_rec.shape[1] != n:
            raise SnnccError(f"must be square (N, N[, S]) with N >= 1 hidden neurons, got {w_rec.shape}",
                             field="weights_rec")
        put("weights_rec", w_rec)
        w_in = _integers("weights_in", self.weights_in, ndims=(2, 3))
        if w_in.shape[0] < 1 or not 1 <= w_in.shape[1] <= n:
            raise SnnccError(f"must be (Nin, N_ien[, S]) with Nin >= 1 and 1 <= N_ien <= N = {n}, got {w_in.shape}",
                             field="weights_in")
        put("weights_in", w_in)
        for name, w in (("weights_in", w_in), ("weights_rec", w_rec)):
            if w.ndim == 3 and not 1 <= w.shape[2] <= CORE.hidden_synapse_states:
                raise SnnccError(f"the synapse axis must have 1 to {CORE.hidden_synapse_states} entries, got "
                                 f"{w.shape[2]}", field=name)
        w_out = _integers("weights_out", self.weights_out, ndims=(2,))
        if not 1 <= w_out.shape[0] <= n or w_out.shape[1] < 1:
            raise SnnccError(f"must be (N_oen, Nout) with 1 <= N_oen <= N = {n} and Nout >= 1, got {w_out.shape}",
                             field="weights_out")
        put("weights_out", w_out)
        n_out = w_out.shape[1]
        for name in HIDDEN_FIELDS:
            put(name, _integers(name, getattr(self, name), shape=(n,)))
        for name in OUTPUT_FIELDS:
            put(name, _integers(name, getattr(self, name), shape=(n_out,)))
        for name in SHIFT_FIELDS:
            put(name, _shift(name, getattr(self, name)))
        put("aliases", _aliases(self.aliases, n))
        put("dt", _dt(self.dt))

    # -- sizes -------------------------------------------------------------------------------------
    @property
    def n_in(self) -> int:
        return self.weights_in.shape[0]

    @property
    def n_hidden(self) -> int:
        return self.weights_rec.shape[0]

    @property
    def n_out(self) -> int:
        return self.weights_out.shape[1]

    @property
    def n_ien(self) -> int:
        """Input expansion neurons: hidden neurons 0 .. n_ien - 1 take the input weights."""
        return self.weights_in.shape[1]

    @property
    def n_oen(self) -> int:
        """Output expansion neurons: the last n_oen hidden neurons give the output weights."""
        return self.weights_out.shape[0]

    @property
    def synapses_used(self) -> int:
        """1 if no weight reaches synapse 2 (Isyn2) by its shape, else 2."""
        return max(w.shape[2] if w.ndim == 3 else 1 for w in (self.weights_in, self.weights_rec))

    def fanout(self) -> np.ndarray:
        """(N,) distinct recurrent targets of each hidden neuron (a target counts once for both synapses)."""
        w = self.weights_rec if self.weights_rec.ndim == 3 else self.weights_rec[:, :, None]
        return np.count_nonzero(np.any(w != 0, axis=2), axis=1)

    # -- conversions -------------------------------------------------------------------------------
    def kwargs(self) -> dict:
        """The keyword arguments of ``XyloSim.from_specification`` (arrays, ints, list of lists, dt)."""
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["aliases"] = [list(a) for a in self.aliases]
        return out

    def __eq__(self, other) -> bool:
        if not isinstance(other, XyloSpec):
            return NotImplemented
        for f in fields(self):
            a, b = getattr(self, f.name), getattr(other, f.name)
            if isinstance(a, np.ndarray):
                if a.dtype != b.dtype or not np.array_equal(a, b):
                    return False
            elif a != b:
                return False
        return True

    __hash__ = None

    # -- chip limits -------------------------------------------------------------------------------
    def chip_violations(self, chip: str | XyloChip | None = None) -> list[tuple[str, str]]:
        """(field, rule with the numbers) for every limit of ``chip`` this network exceeds."""
        c = get_chip(chip)
        out = []

        def limit(field, what, value, most):
            if value > most:
                out.append((field, f"{c.name} ({c.part_number}) has at most {most} {what}; this network needs {value}"))

        limit("weights_in", "input channels", self.n_in, c.max_inputs)
        limit("weights_rec", "hidden neurons", self.n_hidden, c.max_hidden)
        limit("weights_out", "output neurons", self.n_out, c.max_outputs)
        limit("weights_in", "input expansion neurons (hidden neurons reached by input weights)", self.n_ien,
              c.max_input_expansion)
        limit("weights_out", "output expansion neurons (hidden neurons with output weights)", self.n_oen,
              c.max_output_expansion)
        for name, w in (("weights_in", self.weights_in), ("weights_rec", self.weights_rec)):
            if w.ndim == 3:
                limit(name, "synaptic input(s) per hidden neuron (the weights' last axis)", w.shape[2],
                      c.synapses_per_hidden)
        fan = self.fanout()
        if fan.size and int(fan.max()) > c.max_fanout:
            k = int(np.argmax(fan))
            out.append(("weights_rec", f"{c.name} ({c.part_number}) allows a fan-out of at most {c.max_fanout} "
                                       f"recurrent targets per hidden neuron; neuron {k} has {int(fan[k])}"))
        most = max((len(a) for a in self.aliases), default=0)
        if most > c.max_alias_targets:
            k = next(i for i, a in enumerate(self.aliases) if len(a) == most)
            out.append(("aliases", f"{c.name} ({c.part_number}) allows at most {c.max_alias_targets} alias "
                                   f"target(s) per hidden neuron; neuron {k} has {most}"))
        return out

    def check_chip(self, chip: str | XyloChip | None = None, *, file: str | None = None) -> None:
        """Raise the first limit of ``chip`` this network exceeds, as one ``SnnccError`` line."""
        problems = self.chip_violations(chip)
        if problems:
            name, rule = problems[0]
            raise SnnccError(rule, file=file, field=name)

    # -- files -------------------------------------------------------------------------------------
    def npz_arrays(self) -> dict[str, np.ndarray]:
        """The arrays ``save_npz`` writes (pickle-free)."""
        out = {name: getattr(self, name) for name in WEIGHT_FIELDS + HIDDEN_FIELDS + OUTPUT_FIELDS}
        for name in SHIFT_FIELDS:
            out[name] = np.array(getattr(self, name), dtype=FIELD_TYPES[name][0])
        width = max((len(a) for a in self.aliases), default=0)
        table = np.full((self.n_hidden, width), -1, dtype=ALIAS_DTYPE)
        for i, targets in enumerate(self.aliases):
            table[i, :len(targets)] = targets
        out["aliases"] = table
        out["dt"] = np.array(self.dt, dtype=DT_DTYPE)
        return out

    def save_npz(self, path) -> None:
        """Write ``path`` atomically (complete or not at all)."""
        from snncc.targets.kit.writing import write_npz_atomic

        write_npz_atomic(path, self.npz_arrays())

    @classmethod
    def load_npz(cls, path) -> "XyloSpec":
        """Read a spec.npz written by ``save_npz``; anything malformed is one ``SnnccError`` line."""
        return load_npz(path)


# -- reading -----------------------------------------------------------------------------------------
_READ_ERRORS = (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error, KeyError)


def _expected_ndim(name: str) -> tuple[int, ...]:
    if name in ("weights_in", "weights_rec"):
        return (2, 3)
    if name in ("weights_out", "aliases"):
        return (2,)
    if name in SHIFT_FIELDS or name == "dt":
        return (0,)
    return (1,)


def _expected_dtype(name: str) -> np.dtype:
    if name == "aliases":
        return np.dtype(ALIAS_DTYPE)
    if name == "dt":
        return np.dtype(DT_DTYPE)
    return np.dtype(FIELD_TYPES[name][0])


def _member_header(archive: zipfile.ZipFile, name: str):
    """(shape, fortran_order, dtype) of member ``name``.npy, read from its header without its data."""
    with archive.open(name + ".npy") as f:
        version = np.lib.format.read_magic(f)
        if version == (1, 0):
            return np.lib.format.read_array_header_1_0(f)
        if version == (2, 0):
            return np.lib.format.read_array_header_2_0(f)
        raise ValueError(f"unsupported .npy format version {version}")


def _largest_shape(name: str) -> int:
    """The most elements a member may declare (the largest chip's sizes, generously)."""
    n = max(c.max_hidden for c in _all_chips())
    return {"weights_rec": n * n * CORE.hidden_synapse_states, "aliases": n * MAX_ALIASES_STORED}.get(name, n * 64)


def _all_chips():
    from snncc.targets.xylo.chip import CHIPS

    return CHIPS.values()


def load_npz(path) -> XyloSpec:
    """``XyloSpec`` from a spec.npz (``np.load(allow_pickle=False)``), refusing in one line: a file that
    is not an .npz, a missing or extra member, a wrong dtype or number of axes, a declared size
    beyond the largest chip, or any field that breaks the record's rules."""
    shown = str(path)
    try:
        npz = np.load(path, allow_pickle=False)
    except FileNotFoundError:
        raise SnnccError("no such file", file=shown, field="path") from None
    except _READ_ERRORS as ex:
        raise SnnccError(f"not a readable .npz archive ({type(ex).__name__}: {ex})", file=shown,
                         field="format") from None
    if not isinstance(npz, np.lib.npyio.NpzFile):
        raise SnnccError("is a single .npy array, not a spec .npz archive", file=shown, field="format")
    with npz:
        members = set(npz.files)
        missing = [k for k in NPZ_KEYS if k not in members]
        if missing:
            raise SnnccError(f"missing member(s) {', '.join(missing)}", file=shown, field=missing[0])
        extra = sorted(members - set(NPZ_KEYS))
        if extra:
            raise SnnccError(f"unexpected member(s) {', '.join(extra)}; a spec holds exactly {', '.join(NPZ_KEYS)}",
                             file=shown, field=extra[0])
        values = {}
        for name in NPZ_KEYS:
            try:
                shape, fortran, dtype = _member_header(npz.zip, name)
            except _READ_ERRORS as ex:
                raise SnnccError(f"unreadable member ({type(ex).__name__}: {ex})", file=shown, field=name) from None
            if dtype != _expected_dtype(name):
                raise SnnccError(f"must have dtype {_expected_dtype(name)}, got {dtype}", file=shown, field=name)
            if len(shape) not in _expected_ndim(name):
                raise SnnccError(f"must have {' or '.join(str(d) for d in _expected_ndim(name))} axes, got shape "
                                 f"{shape}", file=shown, field=name)
            if math.prod(shape) > _largest_shape(name):
                raise SnnccError(f"declares shape {shape}, larger than any Xylo chip holds", file=shown, field=name)
            try:
                values[name] = npz[name]
            except _READ_ERRORS as ex:
                raise SnnccError(f"unreadable member ({type(ex).__name__}: {ex})", file=shown, field=name) from None
    try:
        return XyloSpec(**values)
    except SnnccError as err:
        raise err.with_file(shown) from None
