"""Hostile sizes, values and options through the CLI: one line, exit 2, no output file, input intact.

Sizes are bounded before anything is allocated (snncc.limits), so every huge declaration here is
refused in milliseconds; options that do not apply to the input or target are refused, defaults
are not.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
import torch

from snncc_test_helpers import TH1_PARAMS, run_cli
from snncc.frontends.checkpoint import save_checkpoint
from snncc.models import SNNConfig, SpikingClassifier

N_IN, N_OUT, STEPS = 3, 4, 20


def refused(capsys, args, *, needle: str, out: Path | None = None, inputs=()) -> str:
    """Run ``snncc args``; assert one ``snncc: error:`` line holding ``needle``, exit 2, nothing written."""
    before = {Path(p): Path(p).read_bytes() for p in inputs}
    code, stdout, err = run_cli(args, capsys)
    lines = err.strip().splitlines()
    assert code == 2, (code, stdout, err)
    assert len(lines) == 1 and lines[0].startswith("snncc: error: "), err
    assert needle in lines[0], lines[0]
    assert "Traceback" not in stdout + err
    if out is not None:
        assert not Path(out).exists()
        assert not list(Path(out).parent.glob(Path(out).name + "*.part*"))
    for p, data in before.items():
        assert p.read_bytes() == data, f"{p} changed"
    return lines[0]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A 3-input, 4-class RSNN as a checkpoint, its Loihi bundle and Jetson artefact, a weight list,
    parameters, a NIR graph and spike inputs (built once for the module)."""
    d = tmp_path_factory.mktemp("hostile")
    torch.manual_seed(0)
    model = SpikingClassifier(SNNConfig(n_inputs=N_IN, n_hidden=8, n_outputs=N_OUT, input_copies=1))
    model.reset_parameters(fwd_weight_scale=3.0)
    save_checkpoint(model, d / "m.pt")
    (d / "p.txt").write_text(TH1_PARAMS)
    torch.save([w.detach().clone() for w in model.weight_list()], d / "w.pt")   # W_in has 3 inputs: copies 1
    (d / "p1.txt").write_text(TH1_PARAMS.replace("nb_input_copies 2", "nb_input_copies 1"))
    from snncc.cli.main import run

    assert run(["compile", str(d / "m.pt"), "-t", "loihi", "-o", str(d / "m.net")]) == 0
    assert run(["compile", str(d / "m.pt"), "-t", "jetson", "-o", str(d / "jet"), "--time-steps", str(STEPS)]) == 0
    rng = np.random.default_rng(0)
    np.save(d / "x.npy", (rng.random((2, STEPS, N_IN)) < 0.2).astype(np.uint8))
    np.save(d / "x2.npy", np.full((2, STEPS, N_IN), 2, np.uint8))
    np.save(d / "b0.npy", np.zeros((0, STEPS, N_IN), np.uint8))
    np.save(d / "t0.npy", np.zeros((2, 0, N_IN), np.uint8))
    _nir(d / "g.nir")
    return d


def _nir(path: Path, weight=None) -> None:
    import nir

    n = 4
    w = np.random.default_rng(0).normal(size=(n, N_IN)) if weight is None else weight
    graph = nir.NIRGraph(nodes={
        "input": nir.Input(input_type={"input": np.array([N_IN])}),
        "fc": nir.Affine(weight=w, bias=np.zeros(n)),
        "lif": nir.CubaLIF(tau_syn=np.full(n, 0.005), tau_mem=np.full(n, 0.02), r=np.full(n, 20.0),
                           v_leak=np.zeros(n), v_threshold=np.ones(n), w_in=np.full(n, 5.0)),
        "output": nir.Output(output_type={"output": np.array([n])}),
    }, edges=[("input", "fc"), ("fc", "lif"), ("lif", "output")])
    nir.write(str(path), graph)


def _edit_h5(src: Path, dst: Path, key: str, **dataset) -> Path:
    """Copy an HDF5 file and replace dataset ``key`` (declared shape only, or data)."""
    shutil.copy(src, dst)
    with h5py.File(dst, "r+") as f:
        if key.endswith("*"):   # the first dataset whose path ends with the rest
            found = []
            f.visititems(lambda k, o: found.append(k) if k.endswith(key[:-1]) else None)
            key = found[0]
        parent, name = key.rsplit("/", 1)
        if name in f[parent]:
            del f[parent][name]
        f[parent].create_dataset(name, **dataset)
    return dst


def _checkpoint_with(files: Path, tmp_path: Path, name: str, arch=None, state=None) -> Path:
    rec = torch.load(files / "m.pt", weights_only=True)
    rec["architecture"] = {**rec["architecture"], **(arch or {})}
    if state is not None:
        rec["state_dict"] = {k: state(v) for k, v in rec["state_dict"].items()}
    path = tmp_path / name
    torch.save(rec, path)
    return path


# -- sizes and values in model files ---------------------------------------------------------------
@pytest.mark.parametrize("arch, needle", [
    ({"n_hidden": 10**7}, "more than snncc allows"),        # 10**14 recurrent weights: ~800 TB
    ({"n_hidden": 0}, "architecture.n_hidden: must be >= 1"),
    ({"n_hidden": -5}, "architecture.n_hidden: must be >= 1"),
    ({"input_copies": 0}, "architecture.input_copies: must be >= 1"),
    ({"n_outputs": 2.5}, "architecture.n_outputs: must be a whole number"),
    ({"tau_mem": -0.1}, "architecture.tau_mem: must be a positive finite number"),
    ({"recurrent": "no"}, "architecture.recurrent: must be true or false"),
    ({"dt": 1e-300}, "snncc.limits.MAX_TIME_STEPS"),
])
def test_checkpoint_architecture_bounded(files, tmp_path, capsys, arch, needle):
    path = _checkpoint_with(files, tmp_path, "a.pt", arch=arch)
    out = tmp_path / "o.snnir"
    refused(capsys, ["compile", path, "-t", "ir", "-o", out], needle=needle, out=out, inputs=[path])


def test_complex_weights_refused_in_checkpoint_and_weight_list(files, tmp_path, capsys):
    path = _checkpoint_with(files, tmp_path, "c.pt", state=lambda v: v.to(torch.complex64))
    out = tmp_path / "o.snnir"
    refused(capsys, ["compile", path, "-o", out], needle="complex", out=out, inputs=[path])
    ws = torch.load(files / "w.pt", weights_only=True)
    torch.save([ws[0].to(torch.complex64) + 1j, ws[1], ws[2]], tmp_path / "cw.pt")
    refused(capsys, ["compile", tmp_path / "cw.pt", "--params", files / "p1.txt", "-o", out],
            needle="W_in: complex values", out=out, inputs=[tmp_path / "cw.pt"])


@pytest.mark.parametrize("variant, needle", [
    ("bytes", "text (|S"),
    ("complex", "complex values"),
    ("declared", "/fc/weight: the declared dataset"),
])
def test_nir_weights_must_be_real_and_fit(files, tmp_path, capsys, variant, needle):
    w = np.random.default_rng(0).normal(size=(4, N_IN))
    spec = {"bytes": dict(data=np.array([[str(v).encode() for v in row] for row in w])),
            "complex": dict(data=w.astype(np.complex128) + 1j),
            "declared": dict(shape=(10**9, 48), dtype="float64", chunks=(1024, 48))}[variant]
    bad = _edit_h5(files / "g.nir", tmp_path / "bad.nir", "fc/weight*", **spec)
    assert bad.stat().st_size < 100_000
    out = tmp_path / "o.snnir"
    refused(capsys, ["compile", bad, "-o", out], needle=needle, out=out, inputs=[bad])


@pytest.mark.parametrize("missing", ["node/edges", "node/nodes"])
def test_nir_graph_without_edges_or_nodes_is_one_line(files, tmp_path, capsys, missing):
    bad = tmp_path / "bad.nir"
    shutil.copy(files / "g.nir", bad)
    with h5py.File(bad, "r+") as f:
        del f[missing]
    out = tmp_path / "o.snnir"
    # snncc's own line, not nir.read's KeyError text: the field is the missing group
    needle = f"bad.nir: /{missing}: missing: a NIR graph lists its {missing.split('/')[1]} in /{missing}"
    refused(capsys, ["compile", bad, "-o", out], needle=needle, out=out, inputs=[bad])
    refused(capsys, ["inspect", bad], needle=needle, inputs=[bad])


def test_nir_sub_graph_without_edges_and_file_without_node_are_one_line(tmp_path, capsys):
    import nir

    lif = nir.LIF(tau=np.full(2, 1e-2), r=np.ones(2), v_leak=np.zeros(2), v_threshold=np.ones(2))
    sub = nir.NIRGraph(nodes={"input": nir.Input(np.array([2])), "lif": lif, "output": nir.Output(np.array([2]))},
                       edges=[("input", "lif"), ("lif", "output")], type_check=False)
    top = nir.NIRGraph(nodes={"input": nir.Input(np.array([2])), "sub": sub, "output": nir.Output(np.array([2]))},
                       edges=[("input", "sub"), ("sub", "output")], type_check=False)
    bad = tmp_path / "bad.nir"
    nir.write(str(bad), top)
    with h5py.File(bad, "r+") as f:
        del f["node/nodes/sub/edges"]
    refused(capsys, ["inspect", bad, "--dt", "1e-3"],
            needle="bad.nir: /node/nodes/sub/edges: missing: a NIR graph lists its edges", inputs=[bad])
    empty = tmp_path / "empty.nir"
    with h5py.File(empty, "w") as f:
        f["version"] = "1.0"
    refused(capsys, ["inspect", empty, "--dt", "1e-3"],
            needle="empty.nir: /node: missing: a NIR file stores its graph in the group /node", inputs=[empty])


def _conv_nir(path: Path) -> Path:
    """A 1x8x8 -> Conv2d(2, 3x3) -> IF graph."""
    import nir

    conv = nir.Conv2d(input_shape=(8, 8), weight=np.ones((2, 1, 3, 3)), stride=1, padding=0, dilation=1, groups=1,
                      bias=np.zeros(2))
    graph = nir.NIRGraph(nodes={
        "input": nir.Input(input_type={"input": np.array([1, 8, 8])}), "conv": conv,
        "flat": nir.Flatten(input_type={"input": np.array([2, 6, 6])}, start_dim=0),
        "lif": nir.IF(r=np.ones(72), v_threshold=np.ones(72)),
        "output": nir.Output(output_type={"output": np.array([72])}),
    }, edges=[("input", "conv"), ("conv", "flat"), ("flat", "lif"), ("lif", "output")])
    nir.write(str(path), graph)
    return path


@pytest.mark.parametrize("key, spec, needle", [
    ("conv/weight", dict(data=np.ones((2, 1, 3, 3)) * (1 + 1j)), "node 'conv'.weight: complex values"),
    ("conv/bias", dict(data=np.zeros(2) + 1j), "node 'conv'.bias: complex values"),
    ("conv/stride", dict(data=np.array([0, 0])), "node 'conv'.stride: must be >= 1, got [0, 0]"),
    ("conv/dilation", dict(data=np.array([0, 1])), "node 'conv'.dilation: must be >= 1"),
    ("conv/padding", dict(data=np.array([-1, 0])), "node 'conv'.padding: must be >= 0"),
])
def test_nir_convolution_fields_must_be_real_and_in_range(tmp_path, capsys, key, spec, needle):
    good = _conv_nir(tmp_path / "c.nir")
    bad = _edit_h5(good, tmp_path / "bad.nir", f"node/nodes/{key}", **spec)
    out = tmp_path / "o.snnir"
    refused(capsys, ["compile", bad, "-o", out], needle=needle, out=out, inputs=[bad])


@pytest.mark.parametrize("dt", [[], ["--dt", "0.001"]])
@pytest.mark.parametrize("key, needle", [
    ("tau_mem", "node 'lif'.tau_mem: time constants must be positive"),
    ("tau_syn", "node 'lif'.tau_syn: time constants must be positive"),
])
def test_nir_zero_time_constants_refused_before_any_division(files, tmp_path, capsys, dt, key, needle):
    import warnings

    bad = _edit_h5(files / "g.nir", tmp_path / "bad.nir", f"node/nodes/lif/{key}", data=np.zeros(4))
    out = tmp_path / "o.snnir"
    refused(capsys, ["compile", bad, "-o", out, *dt], needle=needle, out=out, inputs=[bad])
    from snncc.errors import SnnccError
    from snncc.frontends import LoadOptions, load_model

    with warnings.catch_warnings(record=True) as caught:   # refused before any division by zero
        warnings.simplefilter("always")
        with pytest.raises(SnnccError, match=needle.split(": ", 1)[1]):
            load_model(bad, LoadOptions(dt=float(dt[1]) if dt else None))
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]


def test_tiny_time_bin_refused(files, tmp_path, capsys):
    params = tmp_path / "p.txt"
    params.write_text(TH1_PARAMS.replace("nb_input_copies 2", "nb_input_copies 1").replace("time_bin_size 5",
                                                                                             "time_bin_size 1e-300"))
    out = tmp_path / "o.snnir"
    refused(capsys, ["compile", files / "w.pt", "--params", params, "-o", out],
            needle="time_bin_size: time_bin_size 1e-300 ms", out=out, inputs=[params, files / "w.pt"])


@pytest.mark.parametrize("key, spec, needle", [
    ("layer/1/weight", dict(shape=(10**9, 48), dtype="int16", chunks=(1024, 48)), "Loihi 1 chip(s) of 128 cores x 1024"),
    ("simulation/tSample", dict(data=np.int64(10**12)), "snncc.limits.MAX_TIME_STEPS"),
    ("simulation/tSample", dict(shape=(10**9,), dtype="int64", chunks=(1024,)), "must hold one value"),
    ("layer/1/delay", dict(shape=(10**9, 3), dtype="uint8", chunks=(1024, 3)), "delays need 1 value"),
    ("layer/1/bias", dict(shape=(10**9,), dtype="int32", chunks=(1024,)), "a layer of 8 needs 1 or 8"),
    ("layer/0/shape", dict(shape=(10**9,), dtype="int64", chunks=(1024,)), "at most 8 belong here"),
    ("snncc/metadata", dict(shape=(10**9,), dtype="S8", chunks=(1024,)), "at most 1 belong here"),
])
def test_bundle_declared_sizes_bounded(files, tmp_path, capsys, key, spec, needle):
    bad = _edit_h5(files / "m.net", tmp_path / "bad.net", key, **spec)
    out = tmp_path / "o.npz"
    line = refused(capsys, ["emulate", bad, "-i", files / "x.npy", "-o", out], needle=needle, out=out,
                   inputs=[bad, files / "x.npy"])
    assert str(bad) in line
    refused(capsys, ["map", bad], needle=needle, inputs=[bad])


# -- inputs ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("name, needle", [
    ("b0.npy", "B = 0 samples"),
    ("t0.npy", "gives 0 time steps"),
    ("x2.npy", "binary (0/1 spikes), found the value 2"),
])
def test_emulate_and_run_share_input_rules(files, tmp_path, capsys, name, needle):
    out = tmp_path / "o.npz"
    x = files / name
    refused(capsys, ["emulate", files / "m.net", "-i", x, "-o", out], needle=needle, out=out, inputs=[x])
    refused(capsys, ["run", files / "jet", "-i", x, "-o", out], needle=needle, out=out, inputs=[x])
    refused(capsys, ["run", files / "jet", "-i", x, "--stream", "-o", out], needle=needle, out=out, inputs=[x])


def test_broken_archive_input_is_one_line_everywhere(files, tmp_path, capsys):
    """A file that starts like a zip archive but is not one (numpy raises BadZipFile)."""
    bad = tmp_path / "bad.npy"
    bad.write_bytes(b"PK\x03\x04" + b"not a zip archive" * 4)
    out = tmp_path / "o.npz"
    refused(capsys, ["emulate", files / "m.net", "-i", bad, "-o", out], needle="BadZipFile", out=out, inputs=[bad])
    refused(capsys, ["run", files / "jet", "-i", bad, "-o", out], needle="BadZipFile", out=out, inputs=[bad])
    refused(capsys, ["report", files / "m.net", "--energy", "--input", bad], needle="BadZipFile", inputs=[bad])
    refused(capsys, ["check", files / "m.pt", "--data", bad], needle="BadZipFile", inputs=[bad])


def test_stream_gap_bounded(files, tmp_path, capsys):
    out = tmp_path / "o.npz"
    args = ["emulate", files / "m.net", "-i", files / "x.npy", "-o", out]
    refused(capsys, args + ["--stream", "--gap", str(10**12)], needle="snncc.limits.MAX_TIME_STEPS", out=out)
    refused(capsys, args + ["--stream", "--gap", "-1"], needle="--gap: must be >= 0", out=out)
    refused(capsys, args + ["--gap", "5"], needle="--gap: applies only to stream mode", out=out)


@pytest.mark.parametrize("labels, needle", [
    ([0, 1, 2, 99], "label 99 is outside the model's 4 classes (0..3)"),
    ([0, 1, -1, 3], "label -1 is outside the model's 4 classes"),
    ([], "B = 0 samples"),
])
@pytest.mark.parametrize("target", ["loihi", "jetson"])
def test_check_labels_and_empty_data(files, tmp_path, capsys, labels, needle, target):
    data = tmp_path / "d.npz"
    np.savez(data, inputs=np.zeros((len(labels), STEPS, N_IN), np.uint8), labels=np.asarray(labels, np.int64))
    refused(capsys, ["check", files / "m.pt", "-t", target, "--data", data], needle=needle, inputs=[data])


# -- all-zero weights: accepted with a note by every loader ------------------------------------------
def test_all_zero_weights_accepted_with_a_note_everywhere(files, tmp_path, capsys):
    ws = torch.load(files / "w.pt", weights_only=True)
    torch.save([torch.zeros_like(w) for w in ws], tmp_path / "zw.pt")
    zero_ckpt = _checkpoint_with(files, tmp_path, "z.pt", state=torch.zeros_like)
    _nir(tmp_path / "z.nir", weight=np.zeros((4, N_IN)))
    for args in (["compile", tmp_path / "zw.pt", "--params", files / "p1.txt"], ["compile", zero_ckpt],
                 ["compile", tmp_path / "z.nir"]):
        out = tmp_path / "o.snnir"
        code, _, err = run_cli(args + ["-o", out], capsys)
        assert code == 0 and out.exists(), err
        assert "note:" in err and "all weights are zero" in err
        code, _, err = run_cli(["inspect", out], capsys)   # the IR file keeps the note
        assert code == 0 and "all weights are zero" in err
        out.unlink()
    code, _, err = run_cli(["compile", zero_ckpt, "-t", "loihi", "-o", tmp_path / "z.net"], capsys)
    assert code == 0 and "all weights are zero" in err, err


# -- options that do not apply -----------------------------------------------------------------------
@pytest.mark.parametrize("extra, needle", [
    (["--dt", "0.001"], "--dt: does not apply to an snncc checkpoint"),
    (["--params", "P"], "--params: does not apply to an snncc checkpoint"),
    (["--reset", "subtract"], "--reset: does not apply to an snncc checkpoint"),
])
@pytest.mark.parametrize("verb", ["compile", "inspect", "export", "check"])
def test_load_options_refused_on_a_checkpoint(files, tmp_path, capsys, extra, needle, verb):
    extra = [files / "p.txt" if a == "P" else a for a in extra]
    out = tmp_path / "o.x"
    args = {"compile": ["-t", "ir", "-o", out], "inspect": [], "export": ["--to", "nir", "-o", out],
            "check": ["--data", files / "x.npy"]}[verb]
    refused(capsys, [verb, files / "m.pt", *extra, *args], needle=needle, out=out, inputs=[files / "m.pt"])


def test_load_options_refused_on_other_formats(files, tmp_path, capsys):
    out = tmp_path / "o.snnir"
    refused(capsys, ["compile", files / "w.pt", "--params", files / "p1.txt", "--dt", "0.001", "-o", out],
            needle="--dt: does not apply to a SpyTorch weight list", out=out)
    refused(capsys, ["compile", files / "g.nir", "--params", files / "p.txt", "-o", out],
            needle="--params: does not apply to a NIR graph", out=out)
    assert run_cli(["compile", files / "m.pt", "-o", out], capsys)[0] == 0
    refused(capsys, ["compile", out, "--reset", "zero", "-o", tmp_path / "o2.snnir"],
            needle="--reset: does not apply to an snncc IR file", out=tmp_path / "o2.snnir")


@pytest.mark.parametrize("target, extra, needle", [
    ("ir", ["--time-steps", "5"], "--time-steps: does not apply to --target ir"),
    ("loihi", ["--jetpack", "5.1"], "--jetpack: does not apply to --target loihi"),
    ("jetson", ["--timing", "paper"], "--timing: does not apply to --target jetson"),
    ("jetson", ["--allow-reset-change"], "--allow-reset-change: does not apply to --target jetson"),
    ("jetson", ["--jetpack", "99"], "unknown JetPack version 99"),
    ("ir", ["--scale", "global"], "--scale: does not apply to --target ir"),
])
def test_target_options_refused(files, tmp_path, capsys, target, extra, needle):
    out = tmp_path / "o.out"
    refused(capsys, ["compile", files / "m.pt", "-t", target, "-o", out, *extra], needle=needle, out=out)


def test_other_verbs_refuse_options_that_do_not_apply(files, tmp_path, capsys):
    data = tmp_path / "d.npz"
    np.savez(data, inputs=np.zeros((2, STEPS, N_IN), np.uint8), labels=np.array([0, 1]))
    refused(capsys, ["check", files / "m.pt", "-t", "jetson", "--data", data, "--stream"],
            needle="--stream: does not apply to --target jetson")
    refused(capsys, ["check", files / "m.pt", "-t", "jetson", "--data", data, "--scale", "global"],
            needle="--scale: does not apply to --target jetson")
    refused(capsys, ["map", files / "m.net", "--timing", "paper"], needle="--timing: does not apply to a written artefact (compile fixed it)")
    refused(capsys, ["report", files / "m.net", "--energy", "--input", files / "x.npy", "--seed", "3"],
            needle="--seed: applies only to random inputs")
    refused(capsys, ["report", files / "m.net", "--energy", "--samples", str(10**9)],
            needle="--samples: 1,000,000,000 random samples of")


def test_training_sizes_are_checked_before_torch_allocates(monkeypatch):
    """Every array training builds (weights, a batch's hidden spikes) is held to snncc.limits' memory rule."""
    from snncc.errors import SnnccError
    from snncc.models.size import check_snn_size

    monkeypatch.setenv("SNNCC_MAX_MEMORY", str(2**30))        # the same bound on every machine
    check_snn_size(24, 2, 450, 28, True, 128, 270)          # the paper's RSNN: fine
    with pytest.raises(SnnccError, match="hidden: 1,000,000,000 hidden neurons: the input weights"):
        check_snn_size(24, 2, 10**9, 28, True, 128, 270)
    with pytest.raises(SnnccError, match="hidden: 100,000 hidden neurons: the recurrent weights"):
        check_snn_size(24, 2, 10**5, 28, True, 1, 1)
    check_snn_size(24, 2, 10**5, 28, False, 1, 1)            # an FFSNN has no (H, H) matrix
    monkeypatch.setenv("SNNCC_MAX_MEMORY", str(10**6))
    with pytest.raises(SnnccError, match="batch_size: 450 hidden neurons: one batch's hidden spikes"):
        check_snn_size(24, 2, 450, 28, True, 128, 270)


# -- data sets that do not fit their own classes or the model ---------------------------------------
def _event_set(path: Path, labels, classes) -> Path:
    """An encoded event set written without snncc's checks (as a hostile file would be)."""
    import json

    labels = np.asarray(labels, np.int64)
    x = (np.random.default_rng(0).random((labels.size, 12, 24)) < 0.1).astype(np.uint8)
    meta = {"kind": "events", "threshold": 1, "time_bin_size_ms": 5, "dt_s": 0.005, "n_steps": 12,
            "classes": classes, "synthetic": True, "source": "test", "seed": 0}
    np.savez(path, inputs=x, labels=labels, meta=np.array(json.dumps(meta)))
    return path


@pytest.mark.parametrize("classes, needle", [
    (["a", "b"], "meta.classes: names 2 classes but the labels reach 26"),
    ([], "meta.classes: must be a non-empty list"),
    ("abc", "meta.classes: must be a non-empty list"),
])
def test_data_set_classes_must_name_every_label(files, tmp_path, capsys, classes, needle):
    data = _event_set(tmp_path / "d.npz", np.arange(162) % 27, classes)
    out = tmp_path / "o.pt"
    refused(capsys, ["train", "ffsnn", "--data", data, "--epochs", "1", "-o", out], needle=needle, out=out,
            inputs=[data])
    refused(capsys, ["bench", files / "jet", "--data", data], needle=needle, inputs=[data])


def test_qat_refuses_data_with_more_classes_than_the_model(tmp_path, capsys):
    torch.manual_seed(0)
    model = SpikingClassifier(SNNConfig(n_inputs=24, n_hidden=8, n_outputs=4, input_copies=1))
    save_checkpoint(model, tmp_path / "m4.pt", {"dt": 0.005})
    data = _event_set(tmp_path / "d.npz", np.arange(162) % 27, [str(i) for i in range(27)])
    out = tmp_path / "q.pt"
    refused(capsys, ["train", "rsnn", "--data", data, "--qat-from", tmp_path / "m4.pt", "--qat-epochs", "1",
                     "-o", out], needle="labels: labels reach 26; the model in", out=out,
            inputs=[data, tmp_path / "m4.pt"])
    small = SpikingClassifier(SNNConfig(n_inputs=3, n_hidden=8, n_outputs=28, input_copies=1))
    save_checkpoint(small, tmp_path / "m3.pt", {"dt": 0.005})
    refused(capsys, ["train", "rsnn", "--data", data, "--qat-from", tmp_path / "m3.pt", "--qat-epochs", "1",
                     "-o", out], needle="inputs: has 24 input channels; the model in", out=out)


def test_train_output_is_checked_before_training(tmp_path, capsys, monkeypatch):
    """-o naming the data, a directory, or a place nothing can be written is refused before any epoch."""
    import os
    import subprocess

    import snncc.training.pipeline as pipeline

    def no_training(*args, **kwargs):
        raise AssertionError("training started before the output was checked")

    monkeypatch.setattr(pipeline, "train_model", no_training)
    data = _event_set(tmp_path / "d.npz", np.arange(162) % 27, [str(i) for i in range(27)])
    (tmp_path / "dir").mkdir()
    args = ["train", "ffsnn", "--data", data, "--epochs", "1", "-o"]
    refused(capsys, args + [data], needle="is an input of this command", inputs=[data])
    refused(capsys, args + [tmp_path / "dir"], needle="is a directory")
    locked = tmp_path / "locked"
    locked.mkdir()
    if os.geteuid() != 0:
        locked.chmod(0o555)
        refused(capsys, args + [locked / "m.pt"], needle="EACCES", out=locked / "m.pt")
    elif subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=16k", "tmpfs", str(locked)],
                        capture_output=True).returncode == 0:
        try:
            refused(capsys, args + [locked / "sub" / "m.pt"], needle="EROFS", out=locked / "sub" / "m.pt")
        finally:
            subprocess.run(["umount", str(locked)], capture_output=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.npz", "dir", "locked"]
    assert list((tmp_path / "dir").iterdir()) == [] and list(locked.iterdir()) == []
