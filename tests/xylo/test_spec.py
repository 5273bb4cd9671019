"""XyloSpec: from_specification's keyword arguments as a checked record, each chip's limits, and
spec.npz (atomic, pickle-free) with one-line refusals of anything malformed."""

from __future__ import annotations

import dataclasses
import io
import zipfile

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.targets.xylo.chip import AUDIO2, AUDIO3, CHIPS, CORE, IMU, get_chip
from snncc.targets.xylo.spec import NPZ_KEYS, XyloSpec, load_npz
from tests.xylo.networks import Knobs, chip_sized_knobs, random_spec

# the keyword arguments of rockpool's XyloSim.from_specification (syns61201 and syns63300, 3.1.0),
# less its simulator switches (verify_config, output_mode)
FROM_SPECIFICATION = ("weights_in", "weights_out", "weights_rec", "dash_mem", "dash_mem_out", "dash_syn",
                      "dash_syn_2", "dash_syn_out", "threshold", "threshold_out", "bias", "bias_out",
                      "weight_shift_in", "weight_shift_rec", "weight_shift_out", "aliases", "dt")


def small(**overrides) -> dict:
    fields = dict(weights_in=[[1, -2, 3]], weights_rec=np.zeros((3, 3, 2), int), weights_out=[[1], [2]],
                  dash_mem=[1, 2, 3], dash_syn=[4, 5, 6], dash_syn_2=[7, 8, 9], dash_mem_out=[10], dash_syn_out=[11],
                  threshold=[100, 200, 300], threshold_out=[50], bias=[0, -5, 5], bias_out=[7],
                  weight_shift_in=1, weight_shift_rec=2, weight_shift_out=3, aliases=[[1], [], [0]], dt=1e-3)
    fields.update(overrides)
    return fields


def refused(match: str, **overrides) -> SnnccError:
    with pytest.raises(SnnccError, match=match) as info:
        XyloSpec(**small(**overrides))
    assert "\n" not in str(info.value)
    return info.value


def test_fields_are_exactly_the_keyword_arguments_of_from_specification():
    assert {f.name for f in dataclasses.fields(XyloSpec)} == set(FROM_SPECIFICATION)
    spec = XyloSpec(**small())
    kwargs = spec.kwargs()
    assert set(kwargs) == set(FROM_SPECIFICATION)
    assert kwargs["aliases"] == [[1], [], [0]] and isinstance(kwargs["weight_shift_in"], int)
    assert set(NPZ_KEYS) == set(FROM_SPECIFICATION)


def test_integer_dtypes_sizes_and_read_only_arrays():
    spec = XyloSpec(**small())
    assert spec.weights_in.dtype == np.int8 and spec.weights_rec.dtype == np.int8 and spec.weights_out.dtype == np.int8
    assert spec.dash_mem.dtype == np.uint8 and spec.dash_syn_out.dtype == np.uint8
    assert spec.threshold.dtype == np.int16 and spec.bias_out.dtype == np.int16
    assert (spec.n_in, spec.n_hidden, spec.n_out, spec.n_ien, spec.n_oen) == (1, 3, 1, 3, 2)
    assert spec.synapses_used == 2
    with pytest.raises(ValueError):
        spec.threshold[0] = 1


@pytest.mark.parametrize("overrides,field,match", [
    (dict(weights_rec=np.zeros((3, 2), int)), "weights_rec", "square"),
    (dict(weights_rec=np.zeros((3, 3, 3), int)), "weights_rec", "synapse axis must have 1 to 2"),
    (dict(weights_in=np.zeros((1, 4), int)), "weights_in", r"N_ien <= N = 3"),
    (dict(weights_out=np.zeros((4, 1), int)), "weights_out", r"N_oen <= N = 3"),
    (dict(weights_out=np.zeros((2, 0), int)), "weights_out", "Nout >= 1"),
    (dict(dash_mem=[1, 2]), "dash_mem", r"shape \(3,\)"),
    (dict(threshold_out=[1, 2]), "threshold_out", r"shape \(1,\)"),
    (dict(weights_in=[[1.0, 2.0, 3.0]]), "weights_in", "must hold integers"),
    (dict(bias=[True, False, True]), "bias", "must hold integers"),
    (dict(weights_in=[[128, 0, 0]]), "weights_in", r"\[-128, 127\], found 128"),
    (dict(dash_syn_2=[0, 16, 0]), "dash_syn_2", r"\[0, 15\], found 16"),
    (dict(threshold=[0, 40000, 0]), "threshold", r"\[-32768, 32767\], found 40000"),
    (dict(bias_out=[-40000]), "bias_out", r"found -40000"),
    (dict(weight_shift_rec=16), "weight_shift_rec", r"\[0, 15\], got 16"),
    (dict(weight_shift_in=-1), "weight_shift_in", r"got -1"),
    (dict(weight_shift_out=1.5), "weight_shift_out", "one integer"),
    (dict(aliases=[[1], []]), "aliases", r"one list of alias targets per hidden neuron \(N = 3\)"),
    (dict(aliases=[[3], [], []]), "aliases", r"neuron 0: target 3 is not a hidden-neuron index in \[0, 2\]"),
    (dict(aliases=[[0.5], [], []]), "aliases", "not a hidden-neuron index"),
    (dict(aliases=np.array([[-1, 1], [-1, -1], [-1, -1]])), "aliases", "padding must be trailing"),
    (dict(dt=0.0), "dt", "> 0"),
    (dict(dt=float("nan")), "dt", "> 0"),
])
def test_inconsistent_or_out_of_range_fields_are_refused_in_one_line(overrides, field, match):
    err = refused(match, **overrides)
    assert err.field == field


def test_aliases_accept_a_padded_table_as_stored_in_npz():
    spec = XyloSpec(**small(aliases=np.array([[1, -1], [-1, -1], [0, 2]], np.int32)))
    assert spec.aliases == ((1,), (), (0, 2))


@pytest.mark.parametrize("chip,overrides,field,numbers", [
    (AUDIO2, dict(n_in=17), "weights_in", "at most 16 input channels; this network needs 17"),
    (AUDIO2, dict(n_hidden=1001, n_ien=1, n_oen=1), "weights_rec", "at most 1000 hidden neurons; this network needs 1001"),
    (AUDIO2, dict(n_out=9), "weights_out", "at most 8 output neurons; this network needs 9"),
    (IMU, dict(n_hidden=200, n_ien=129, n_oen=1), "weights_in", "at most 128 input expansion neurons"),
    (AUDIO3, dict(n_hidden=200, n_ien=1, n_oen=129), "weights_out", "at most 128 output expansion neurons"),
    (IMU, dict(synapse_axis=2), "weights_in", "at most 1 synaptic input"),
    (AUDIO2, dict(n_hidden=70, n_ien=1, n_oen=1, density=1.0), "weights_rec", "fan-out of at most 64"),
])
def test_each_chips_limits_are_refused_with_the_rule_and_the_numbers(chip, overrides, field, numbers):
    base = dict(seed=1, n_in=4, n_hidden=10, n_out=2, n_ien=5, n_oen=5, synapse_axis=0, shift_in=0, shift_rec=0,
                shift_out=0, density=0.1, threshold_scale=1.0, bias_fraction=0.0, alias_fraction=0.0,
                negative_thresholds=False)
    base.update(overrides)
    spec = random_spec(Knobs(**base))
    with pytest.raises(SnnccError) as info:
        spec.check_chip(chip, file="net/spec.npz")
    err = info.value
    assert err.field == field and numbers in err.rule and chip.part_number in err.rule
    assert str(err).startswith("net/spec.npz: ") and "\n" not in str(err)


def test_two_alias_targets_are_more_than_any_chip_allows():
    spec = XyloSpec(**small(aliases=[[1, 2], [], []], weights_rec=np.zeros((3, 3), int)))
    for chip in CHIPS.values():
        assert [f for f, _ in spec.chip_violations(chip)] == ["aliases"]


@pytest.mark.parametrize("key", sorted(CHIPS))
def test_a_network_at_the_chips_limits_passes_its_checks(key):
    spec = random_spec(chip_sized_knobs(CHIPS[key], seed=3))
    assert spec.chip_violations(key) == []


def test_chip_records():
    assert get_chip() is AUDIO2 and get_chip("SYNS63300") is IMU and get_chip(AUDIO3) is AUDIO3
    with pytest.raises(KeyError, match="syns61201"):
        get_chip("loihi")
    assert (AUDIO2.max_hidden, AUDIO2.max_outputs, IMU.max_hidden, IMU.max_outputs, AUDIO3.max_hidden,
            AUDIO3.max_outputs) == (1000, 8, 496, 16, 992, 32)
    assert (CORE.max_input_spikes, CORE.max_hidden_spikes, CORE.max_output_spikes) == (15, 31, 1)
    assert (CORE.state_min, CORE.state_max, CORE.dash_max, CORE.weight_min, CORE.weight_max) == (
        -32768, 32767, 15, -128, 127)
    for chip in CHIPS.values():
        with pytest.raises(dataclasses.FrozenInstanceError):
            chip.max_hidden = 1
        for field in ("max_hidden", "max_outputs", "synapses_per_hidden", "max_input_expansion", "max_fanout"):
            assert chip.source(field), f"{chip.key}.{field} names no source"


# -- spec.npz ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("synapse_axis", [0, 1, 2])
def test_npz_round_trip_is_exact_and_pickle_free(tmp_path, synapse_axis):
    spec = random_spec(Knobs(seed=5, n_in=3, n_hidden=9, n_out=2, n_ien=4, n_oen=6, synapse_axis=synapse_axis,
                             shift_in=3, shift_rec=9, shift_out=15, density=0.5, threshold_scale=1.0,
                             bias_fraction=0.5, alias_fraction=0.5, negative_thresholds=True))
    path = tmp_path / "spec.npz"
    spec.save_npz(path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["spec.npz"]
    with np.load(path, allow_pickle=False) as npz:
        assert set(npz.files) == set(NPZ_KEYS)
        assert npz["weights_in"].dtype == np.int8 and npz["dt"].dtype == np.float64
    assert XyloSpec.load_npz(path) == spec
    assert load_npz(path).kwargs()["aliases"] == [list(a) for a in spec.aliases]


def test_a_failed_save_leaves_the_old_file(tmp_path, monkeypatch):
    spec = XyloSpec(**small())
    path = tmp_path / "spec.npz"
    spec.save_npz(path)
    before = path.read_bytes()

    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(np.lib.format, "write_array", broken)
    with pytest.raises(OSError):
        XyloSpec(**small(dt=2e-3)).save_npz(path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["spec.npz"]


def write_npz(path, arrays: dict, allow_pickle: bool = False) -> None:
    with zipfile.ZipFile(path, "w") as zf:
        for name, value in arrays.items():
            buf = io.BytesIO()
            np.lib.format.write_array(buf, np.asanyarray(value), allow_pickle=allow_pickle)
            zf.writestr(name + ".npy", buf.getvalue())


def good_arrays() -> dict:
    return XyloSpec(**small()).npz_arrays()


def malformed(tmp_path, **changes):
    arrays = good_arrays()
    for key, value in changes.items():
        if value is None:
            del arrays[key]
        else:
            arrays[key] = value
    path = tmp_path / "bad.npz"
    write_npz(path, arrays, allow_pickle=True)
    return path


@pytest.mark.parametrize("changes,field,match", [
    (dict(threshold=None), "threshold", "missing member"),
    (dict(extra=np.zeros(2)), "extra", "unexpected member"),
    (dict(weights_in=np.zeros((1, 3), np.int16)), "weights_in", "must have dtype int8, got int16"),
    (dict(dash_mem=np.zeros(3, np.int8)), "dash_mem", "dtype uint8"),
    (dict(dt=np.array([1e-3])), "dt", "must have 0 axes"),
    (dict(weight_shift_in=np.array(1, np.int64)), "weight_shift_in", "dtype int8"),
    (dict(dash_syn=np.array([1, 16, 2], np.uint8)), "dash_syn", r"\[0, 15\], found 16"),
    (dict(weights_out=np.zeros((5, 1), np.int8)), "weights_out", "N_oen <= N = 3"),
    (dict(aliases=np.array([[7], [-1], [-1]], np.int32)), "aliases", "not a hidden-neuron index"),
    (dict(bias=np.array([None, 1, 2], object)), "bias", "dtype int16, got object"),
    (dict(weights_rec=np.zeros((2000, 2000), np.int8)), "weights_rec", "larger than any Xylo chip holds"),
])
def test_malformed_spec_files_are_refused_in_one_line(tmp_path, changes, field, match):
    path = malformed(tmp_path, **changes)
    with pytest.raises(SnnccError, match=match) as info:
        load_npz(path)
    assert info.value.field == field and info.value.file == str(path) and "\n" not in str(info.value)


@pytest.mark.parametrize("content,match", [
    (b"", "not a readable .npz"),
    (b"not a zip file at all, just words", "not a readable .npz"),
])
def test_files_that_are_not_npz_archives_are_refused(tmp_path, content, match):
    path = tmp_path / "x.npz"
    path.write_bytes(content)
    with pytest.raises(SnnccError, match=match):
        load_npz(path)


def test_a_single_npy_array_a_missing_file_and_a_corrupt_member_are_refused(tmp_path):
    npy = tmp_path / "a.npz"
    with open(npy, "wb") as f:
        np.save(f, np.zeros(3))
    with pytest.raises(SnnccError, match="single .npy array"):
        load_npz(npy)
    with pytest.raises(SnnccError, match="no such file"):
        load_npz(tmp_path / "missing.npz")
    path = tmp_path / "spec.npz"
    XyloSpec(**small()).save_npz(path)
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as zf:
        info = zf.getinfo("weights_rec.npy")
    name_len, extra_len = np.frombuffer(bytes(data[info.header_offset + 26:info.header_offset + 30]), "<u2")
    start = info.header_offset + 30 + int(name_len) + int(extra_len)     # the member's compressed data
    data[start:start + info.compress_size] = bytes(info.compress_size)
    path.write_bytes(bytes(data))
    with pytest.raises(SnnccError, match="weights_rec") as err:
        load_npz(path)
    assert "\n" not in str(err.value)
