"""No read outside the input: paths in a Jetson manifest and links in HDF5 files (bundles, NIR
graphs) that lead to other files are refused in one line, before anything is read from them;
damaged model files inside an artefact are bad input (exit 2), not internal errors."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
import torch

from snncc_test_helpers import run_cli
from snncc.frontends.checkpoint import save_checkpoint
from snncc.models import SNNConfig, SpikingClassifier

N_IN, STEPS = 3, 20


def refused(capsys, args, needle: str) -> str:
    code, out, err = run_cli(args, capsys)
    lines = err.strip().splitlines()
    assert code == 2, (code, out, err)
    assert len(lines) == 1 and lines[0].startswith("snncc: error: "), err
    assert needle in lines[0], lines[0]
    return lines[0]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A small RSNN's Loihi bundle and Jetson artefact, spike inputs, and a secret file outside them."""
    d = tmp_path_factory.mktemp("reads")
    torch.manual_seed(0)
    model = SpikingClassifier(SNNConfig(n_inputs=N_IN, n_hidden=8, n_outputs=4, input_copies=1))
    model.reset_parameters(fwd_weight_scale=3.0)
    save_checkpoint(model, d / "m.pt")
    from snncc.cli.main import run

    assert run(["compile", str(d / "m.pt"), "-t", "loihi", "-o", str(d / "m.net")]) == 0
    assert run(["compile", str(d / "m.pt"), "-t", "jetson", "-o", str(d / "jet"), "--time-steps", str(STEPS)]) == 0
    np.save(d / "x.npy", (np.random.default_rng(0).random((2, STEPS, N_IN)) < 0.2).astype(np.uint8))
    return d


def _jetson_with(files: Path, tmp_path: Path, variant_file: str | None = None, model_bytes: bytes | None = None) -> Path:
    art = tmp_path / "art"
    shutil.copytree(files / "jet", art)
    if variant_file is not None:
        manifest = json.loads((art / "manifest.json").read_text())
        manifest["variants"][0]["file"] = variant_file
        manifest["variants"][1]["file"] = variant_file
        (art / "manifest.json").write_text(json.dumps(manifest))
    if model_bytes is not None:
        (art / "model.onnx").write_bytes(model_bytes)
        (art / "step.onnx").write_bytes(model_bytes)
    return art


def _jetson_commands(art: Path, files: Path, tmp_path: Path) -> list[list]:
    x = files / "x.npy"
    return [["run", art, "-i", x, "-o", tmp_path / "o.npz"], ["run", art, "-i", x, "--stream"],
            ["bench", art, "--samples", "2", "--repeats", "1"], ["bench", art, "--samples", "2", "--stream"],
            ["bench", art, files / "jet", "--samples", "2", "--repeats", "1"]]


@pytest.mark.parametrize("variant_file, needle", [
    ("../../../../../../etc/passwd", "is not a file name inside the artefact"),
    ("/etc/passwd", "is not a file name inside the artefact"),
    ("sub/../../m.pt", "is not a file name inside the artefact"),
    ("link.onnx", "is a symbolic link (it may lead outside the artefact)"),
])
def test_jetson_manifest_paths_stay_inside_the_artefact(files, tmp_path, capsys, monkeypatch, variant_file, needle):
    art = _jetson_with(files, tmp_path, variant_file)
    (tmp_path / "outside.onnx").write_bytes((files / "jet" / "model.onnx").read_bytes())
    (art / "link.onnx").symlink_to(tmp_path / "outside.onnx")
    import onnxruntime

    opened = []
    real = onnxruntime.InferenceSession

    def spy(path, *args, **kwargs):
        opened.append(str(path))
        return real(path, *args, **kwargs)

    monkeypatch.setattr(onnxruntime, "InferenceSession", spy)
    for args in _jetson_commands(art, files, tmp_path):
        line = refused(capsys, args, needle)
        assert line.startswith(f"snncc: error: {art}: manifest.json/variants/0/file: "), line
    assert not [p for p in opened if str(art) in p or "passwd" in p or "outside" in p]
    assert not (tmp_path / "o.npz").exists()


@pytest.mark.parametrize("content", [b"not an onnx model", b""])
def test_damaged_onnx_in_an_artefact_is_bad_input(files, tmp_path, capsys, content):
    art = _jetson_with(files, tmp_path, model_bytes=content)
    for args in _jetson_commands(art, files, tmp_path):
        line = refused(capsys, args, "ONNX Runtime cannot load it (")
        assert f"{art}: model.onnx: " in line or f"{art}: step.onnx: " in line


# -- HDF5 links out of a bundle or a NIR graph -----------------------------------------------------
def _outside(tmp_path: Path, key: str, like) -> Path:
    other = tmp_path / "secret.h5"
    with h5py.File(other, "w") as f:
        f.create_dataset("x", data=np.asarray(like))
    return other


def _relink(src: Path, dst: Path, key: str, how: str, tmp_path: Path) -> Path:
    """Copy ``src`` and make dataset ``key`` lead outside (or around) the file by ``how``."""
    shutil.copy(src, dst)
    with h5py.File(dst, "r+") as f:
        data = f[key][()]
        parent, name = key.rsplit("/", 1)
        del f[parent][name]
        other = _outside(tmp_path, key, data)
        if how == "external_link":
            f[parent][name] = h5py.ExternalLink(str(other), "/x")
        elif how == "soft_link":          # inside the file, but not how an input holds its data
            f.create_dataset("/moved", data=data)
            f[parent][name] = h5py.SoftLink("/moved")
        elif how == "soft_to_external":   # a soft link through an external link
            f["/moved"] = h5py.ExternalLink(str(other), "/x")
            f[parent][name] = h5py.SoftLink("/moved")
        elif how == "external_storage":
            raw = tmp_path / "raw.bin"
            np.ascontiguousarray(data).tofile(raw)
            f[parent].create_dataset(name, shape=data.shape, dtype=data.dtype, external=[(str(raw), 0, data.nbytes)])
        elif how == "virtual":
            layout = h5py.VirtualLayout(shape=data.shape, dtype=data.dtype)
            layout[...] = h5py.VirtualSource(str(other), "x", shape=data.shape)
            f[parent].create_virtual_dataset(name, layout)
    return dst


HOW = ["external_link", "soft_link", "soft_to_external", "external_storage", "virtual"]
NEEDLE = {"external_link": "is an external link to", "soft_link": "is a SoftLink",
          "soft_to_external": "is an external link to",
          "external_storage": "keeps its data in an external file", "virtual": "is a virtual dataset"}


@pytest.mark.parametrize("how", HOW)
def test_bundle_links_to_other_files_are_refused(files, tmp_path, capsys, how):
    bad = _relink(files / "m.net", tmp_path / "bad.net", "layer/1/weight", how, tmp_path)
    out = tmp_path / "o.npz"
    for args in (["emulate", bad, "-i", files / "x.npy", "-o", out], ["map", bad],
                 ["report", bad, "--energy", "--samples", "2"]):
        line = refused(capsys, args, NEEDLE[how])
        assert f"{bad}: " in line
    assert not out.exists()


@pytest.mark.parametrize("how", HOW)
def test_nir_links_to_other_files_are_refused(tmp_path, capsys, how):
    import nir

    w = np.random.default_rng(0).normal(size=(4, N_IN))
    graph = nir.NIRGraph(nodes={
        "input": nir.Input(input_type={"input": np.array([N_IN])}),
        "fc": nir.Affine(weight=w, bias=np.zeros(4)),
        "lif": nir.CubaLIF(tau_syn=np.full(4, 0.005), tau_mem=np.full(4, 0.02), r=np.full(4, 20.0),
                           v_leak=np.zeros(4), v_threshold=np.ones(4), w_in=np.full(4, 5.0)),
        "output": nir.Output(output_type={"output": np.array([4])}),
    }, edges=[("input", "fc"), ("fc", "lif"), ("lif", "output")])
    nir.write(str(tmp_path / "g.nir"), graph)
    bad = _relink(tmp_path / "g.nir", tmp_path / "bad.nir", "node/nodes/fc/weight", how, tmp_path)
    out = tmp_path / "o.snnir"
    for args in (["compile", bad, "-o", out], ["inspect", bad]):
        refused(capsys, args, NEEDLE[how])
    assert not out.exists()
