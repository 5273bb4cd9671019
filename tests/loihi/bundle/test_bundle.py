"""Bundles: round trip, byte identity, SLAYER v1 files, and one-line errors for bad files."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from snncc.errors import SnnccError
from snncc.targets.loihi import target
from snncc.targets.loihi.bundle.read import read_bundle
from snncc.targets.loihi.bundle.write import write_bundle
from snncc.targets.loihi.emulation.emulator import emulate
from snncc_test_helpers import run_cli
from tests.loihi.helpers import random_network, small_graph

FIELDS = ("kind", "n", "wgt_exp", "wgt_exp_rec", "v_th_mant", "i_decay", "v_decay", "ref_delay", "bias_exp")


def _assert_same(a, b):
    assert a.t_sample == b.t_sample and len(a.layers) == len(b.layers)
    for x, y in zip(a.layers, b.layers):
        for f in FIELDS:
            if x.kind != "input" or f in ("kind", "n"):
                assert np.array_equal(getattr(x, f), getattr(y, f)), f
        for f in ("weight", "weight_rec", "bias", "delay", "delay_rec"):
            vx, vy = getattr(x, f), getattr(y, f)
            if x.kind == "input" or (vx is None and vy is None):
                continue
            if f == "bias" and vx is None:
                continue
            assert np.array_equal(np.broadcast_to(vx, np.shape(vy) or np.shape(vx)), np.asarray(vy)), f


def test_bundle_round_trip_and_byte_identity(tmp_path):
    art = target.lower(small_graph(seed=1), {"scale": "global"})
    a, b = tmp_path / "a.net", tmp_path / "b.net"
    art.write(a)
    art2 = target.lower(small_graph(seed=1), {"scale": "global"})
    art2.write(b)
    assert a.read_bytes() == b.read_bytes()
    back = read_bundle(a)
    _assert_same(art.network, back)
    assert back.core_map == art.network.core_map
    assert back.metadata["quantization"]["w_scale"] == art.quantization["w_scale"]
    assert back.metadata["netx_compat"] and [lay.name for lay in back.layers] == ["input", "hidden", "out"]
    x = (np.random.default_rng(0).random((3, 40, 8)) < 0.2).astype(np.uint8)
    r1, r2 = emulate(art.network, x, record="all"), emulate(back, x, record="all")
    assert all(np.array_equal(r1.spikes[i], r2.spikes[i]) for i in r1.spikes)
    with h5py.File(a, "r") as f:      # snncc's own groups live at the root, never under /layer
        assert sorted(f["layer"].keys()) == ["0", "1", "2"] and "snncc" in f


def test_the_bundle_records_the_graph_and_identify_returns_it(tmp_path):
    """``/snncc/model`` holds ``kit.artefact.model_record`` of the graph compiled; ``identify`` returns it as
    ``identity.model`` (None for a bundle that records none: another writer's, or an older snncc's)."""
    from snncc.targets.kit.artefact import model_record

    graph = small_graph(seed=1)
    path = tmp_path / "m.net"
    target.lower(graph, {"scale": "global"}).write(path)
    identity = target.identify(path)
    assert identity.model == model_record(graph) and identity.model["resets"] == {"hidden": "zero", "out": "zero"}
    other = small_graph(seed=1)
    other.node("hidden").reset = "subtract"
    assert model_record(other)["graph_sha256"] != identity.model["graph_sha256"]
    write_bundle(random_network(0), tmp_path / "plain.net")
    assert target.identify(tmp_path / "plain.net").model is None


def test_random_networks_with_per_synapse_delays_and_bias_round_trip(tmp_path):
    for seed in range(4):
        net = random_network(seed, split_exponents=seed >= 2)
        write_bundle(net, tmp_path / "r.net")
        _assert_same(net, read_bundle(tmp_path / "r.net"))


def test_per_neuron_registers_round_trip_and_are_checked(tmp_path):
    net = random_network(1, profiles=True)
    path = tmp_path / "p.net"
    write_bundle(net, path)
    back = read_bundle(path)
    _assert_same(net, back)
    assert any("one value per neuron" in note for note in back.metadata["netx_compat"])
    with h5py.File(path, "r+") as f:
        v = f["layer/1/neuron/vThMant"][()]
        del f["layer/1/neuron/vThMant"]
        f["layer/1/neuron/vThMant"] = v[:-1]
    with pytest.raises(SnnccError, match="vThMant: per-neuron values must be a numeric array of 11"):
        read_bundle(path)
    net.layers[1].v_decay = np.full(11, 5000)
    with pytest.raises(SnnccError, match="decays must lie in 0..4096"):
        write_bundle(net, tmp_path / "q.net")
    assert not (tmp_path / "q.net").exists()


def test_per_synapse_exponents_are_checked_on_read_and_write(tmp_path):
    net = random_network(0, split_exponents=True)
    path = tmp_path / "s.net"
    write_bundle(net, path)
    with h5py.File(path, "r") as f:
        assert f["layer/1/neuron/wgtExp"].shape == net.layers[1].weight.shape
    with h5py.File(path, "r+") as f:
        e = f["layer/1/neuron/wgtExpRec"][()]
        del f["layer/1/neuron/wgtExpRec"]
        f["layer/1/neuron/wgtExpRec"] = e[:, :-1]
    with pytest.raises(SnnccError, match="wgtExpRec: per-synapse exponents must be an integer array shaped"):
        read_bundle(path)
    net.layers[1].wgt_exp = np.full(net.layers[1].weight.shape, 9)
    with pytest.raises(SnnccError, match="weight exponents must lie in -6..7"):
        write_bundle(net, tmp_path / "t.net")
    assert not (tmp_path / "t.net").exists()


def _slayer_v1(path, rng):
    """A file in the layout the paper's authors exported from SLAYER v1."""
    w_in = (rng.integers(-60, 60, (20, 12)) * 2).astype(np.float32)
    w_rec = (rng.integers(-20, 20, (20, 20)) * 2).astype(np.float32)
    w_out = (rng.integers(-60, 60, (5, 20)) * 2).astype(np.float32)
    with h5py.File(path, "w") as f:
        f.create_dataset("simulation/Ts", data=1.0)
        f.create_dataset("simulation/tSample", data=50)
        f.create_dataset("layer/0/type", data=np.array([b"input"]))
        f.create_dataset("layer/0/shape", data=np.array([1, 1, 12]))
        f.create_dataset("layer/1/type", data=np.array([b"flatten"]))
        f.create_dataset("layer/1/shape", data=np.array([12, 1, 1]))
        f.create_dataset("layer/2/type", data=np.array([b"recurrent"]))
        f.create_dataset("layer/2/shape", data=np.array([20, 1, 1]))
        f.create_dataset("layer/2/weight", data=w_in)
        f.create_dataset("layer/2/recWeight", data=w_rec)
        f.create_dataset("layer/3/type", data=np.array([b"dense"]))
        f.create_dataset("layer/3/shape", data=np.array([5, 1, 1]))
        f.create_dataset("layer/3/weight", data=w_out)
        for i in (2, 3):
            n = f.create_group(f"layer/{i}/neuron")
            n.create_dataset("type", data=np.array([b"LOIHI"]))
            n.create_dataset("theta", data=300.0 * 64)
            n.create_dataset("iDecay", data=2315.0)
            n.create_dataset("vDecay", data=327.0)
            n.create_dataset("refDelay", data=1.0)
            n.create_dataset("wgtExp", data=0.0)
            n.create_dataset("tauRho", data=1.0)
            n.create_dataset("scaleRho", data=1.0)
    return w_in, w_rec, w_out


def test_slayer_v1_file_loads_and_emulates(tmp_path, capsys):
    path = tmp_path / "authors.net"
    w_in, w_rec, w_out = _slayer_v1(path, np.random.default_rng(0))
    net = read_bundle(path)
    assert [lay.kind for lay in net.layers] == ["input", "dense_rec", "dense"]
    assert net.metadata["dialect"] == "slayer-v1" and net.t_sample == 50
    assert np.array_equal(net.layers[1].weight_rec, w_rec) and net.layers[1].v_th_mant == 300
    x = (np.random.default_rng(1).random((2, 50, 12)) < 0.3).astype(np.uint8)
    np.save(tmp_path / "x.npy", x)
    code, out, err = run_cli(["emulate", path, "--input", tmp_path / "x.npy", "-o", tmp_path / "o.npz",
                              "--record", "all"], capsys)
    assert code == 0, err
    z = np.load(tmp_path / "o.npz")
    assert z["output_spikes"].shape == (2, 50, 5) and z["layer2_spikes"].shape == (2, 50, 20)  # HDF5 indices
    assert z["layer3_voltage"].shape == (2, 50, 5) and "layer1_spikes" not in z.files     # 1 is the flatten
    assert np.array_equal(z["counts"], emulate(net, x).counts)


def _mutations():
    def odd(f):
        w = f["layer/1/weight"][()]
        w[0, 0] = 3
        del f["layer/1/weight"]
        f["layer/1/weight"] = w

    def big(f):
        w = f["layer/1/weight"][()]
        w[0, 0] = 300
        del f["layer/1/weight"]
        f["layer/1/weight"] = w.astype(np.int32)

    def decay(f):
        del f["layer/2/neuron/vDecay"]
        f["layer/2/neuron/vDecay"] = 5000

    def shape(f):
        w = f["layer/2/weight"][()]
        del f["layer/2/weight"]
        f["layer/2/weight"] = w[:, :-1]

    def strings(f):
        del f["layer/1/weight"]
        f["layer/1/weight"] = np.array([[b"a"]])

    return {
        "odd weight": (odd, "/layer/1/weight: weights must be even"),
        "weight out of range": (big, "/layer/1/weight: weights must lie in [-256, 254]"),
        "decay out of range": (decay, "/layer/2/neuron/vDecay: decays must lie in 0..4096"),
        "shapes do not chain": (shape, "/layer/2/weight: shape"),
        "missing group": (lambda f: f.__delitem__("simulation"), "/simulation: missing group"),
        "missing neuron": (lambda f: f.__delitem__("layer/1/neuron"), "/layer/1/neuron: missing group"),
        "wrong dtype": (strings, "/layer/1/weight: must be a numeric array"),
    }


@pytest.mark.parametrize("name", list(_mutations()))
def test_bad_bundles_give_one_line(tmp_path, capsys, name):
    mutate, needle = _mutations()[name]
    path = tmp_path / "bad.net"
    target.lower(small_graph(seed=1), {"scale": "global"}).write(path)
    with h5py.File(path, "r+") as f:
        mutate(f)
    np.save(tmp_path / "x.npy", np.zeros((5, 8), np.uint8))
    code, out, err = run_cli(["emulate", path, "--input", tmp_path / "x.npy", "-o", tmp_path / "o.npz"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err, err
    assert str(path) in err and not (tmp_path / "o.npz").exists()


def test_not_hdf5_gives_one_line(tmp_path, capsys):
    path = tmp_path / "junk.net"
    path.write_bytes(b"\x00garbage" * 10)
    with pytest.raises(SnnccError, match="not an HDF5 file"):
        read_bundle(path)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_mutated_bundles_never_crash_the_reader(tmp_path_factory, data):
    base = tmp_path_factory.mktemp("fuzz") / "b.net"
    write_bundle(random_network(0), base)
    raw = bytearray(base.read_bytes())
    for _ in range(data.draw(st.integers(1, 20))):
        pos = data.draw(st.integers(0, len(raw) - 1))
        raw[pos] = data.draw(st.integers(0, 255))
    if data.draw(st.booleans()):
        raw = raw[: data.draw(st.integers(0, len(raw)))]
    bad = base.with_name("m.net")
    bad.write_bytes(bytes(raw))
    try:
        net = read_bundle(bad)
    except SnnccError as err:
        assert "\n" not in err.line()
    else:
        emulate(net, np.zeros((1, 3, net.input_width), np.uint8))
