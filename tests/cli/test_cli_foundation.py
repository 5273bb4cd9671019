"""The CLI: every verb listed, compile to IR, and bad input as one line with no output file."""

import os
import pickle
import subprocess
import sys
import zipfile

import pytest
import torch

from snncc_test_helpers import TH1_PARAMS, run_cli
from snncc.frontends.checkpoint import save_checkpoint
from snncc.models import SNNConfig, SpikingClassifier

VERBS = ["compile", "emulate", "check", "map", "report", "export", "data", "train", "bench", "inspect", "run"]


def test_help_lists_every_verb(capsys):
    code, out, _ = run_cli(["--help"], capsys)
    assert code == 0
    for verb in VERBS:
        assert verb in out


def test_targets_import_as_subpackages():
    subprocess.run([sys.executable, "-c", "import snncc.targets.loihi, snncc.targets.jetson"], check=True)


def test_console_script_is_installed():
    out = subprocess.run(["snncc", "--help"], capture_output=True, text=True)
    assert out.returncode == 0 and "compile" in out.stdout


def test_compile_checkpoint_to_ir_and_inspect(tmp_path, small_rsnn_checkpoint, capsys):
    out_file = tmp_path / "m.snnir"
    code, out, err = run_cli(["compile", small_rsnn_checkpoint, "--target", "ir", "-o", out_file], capsys)
    assert code == 0, err
    assert out_file.exists() and "hidden" in out
    code, out, _ = run_cli(["inspect", out_file, "--json"], capsys)
    assert code == 0
    import json
    summary = json.loads(out)
    assert summary["neurons"] == 32 + 28 and summary["metadata"]["update_order"] == "spytorch"


def test_compile_weight_list_with_params(tmp_path, authors_weights, th1_params, capsys):
    code, out, err = run_cli(["compile", authors_weights, "--params", th1_params, "-o", tmp_path / "a.snnir", "--json"], capsys)
    assert code == 0, err
    assert '"source_format": "spytorch-weight-list"' in out


def _bad_files(tmp_path):
    files = {}
    files["random bytes"] = tmp_path / "random.pt"
    files["random bytes"].write_bytes(os.urandom(4096))
    good = tmp_path / "good.pt"
    torch.save({"a": torch.ones(3)}, good)
    files["truncated"] = tmp_path / "truncated.pt"
    files["truncated"].write_bytes(good.read_bytes()[:300])
    files["non-torch zip"] = tmp_path / "plain.zip.pt"
    with zipfile.ZipFile(files["non-torch zip"], "w") as zf:
        zf.writestr("readme.txt", "hello")
    files["empty"] = tmp_path / "empty.pt"
    files["empty"].write_bytes(b"")
    files["bare state dict"] = good
    return files


@pytest.mark.parametrize("kind", ["random bytes", "truncated", "non-torch zip", "empty", "bare state dict"])
@pytest.mark.parametrize("target", ["loihi", "jetson", "ir"])
def test_bad_model_files_give_one_line_and_no_output(tmp_path, capsys, kind, target):
    path = _bad_files(tmp_path)[kind]
    out = tmp_path / {"loihi": "x.net", "jetson": "x_dir", "ir": "x.snnir"}[target]
    code, stdout, err = run_cli(["compile", path, "--target", target, "-o", out], capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("snncc: error: ") and str(path) in lines[0], err
    assert "Traceback" not in err + stdout
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".x")]


class _Payload:
    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (open, (self.marker, "w"))


def test_a_pickle_needing_arbitrary_globals_is_refused_not_executed(tmp_path, capsys):
    marker = tmp_path / "was_executed"
    evil = tmp_path / "evil.pt"
    torch.save([_Payload(str(marker))], evil)
    marker.unlink(missing_ok=True)  # torch.save does not run __reduce__'s callable, but be sure
    code, _, err = run_cli(["compile", evil, "--target", "loihi", "-o", tmp_path / "x.net"], capsys)
    assert code == 2 and "refused" in err and "weights_only" in err
    assert not marker.exists()
    raw = tmp_path / "evil_raw.pt"
    raw.write_bytes(pickle.dumps(_Payload(str(marker))))
    code, _, err = run_cli(["compile", raw, "-o", tmp_path / "x.snnir"], capsys)
    assert code == 2 and not marker.exists()


def _checkpoint_with(tmp_path, mutate):
    model = SpikingClassifier(SNNConfig(n_hidden=8, n_outputs=4))
    path = tmp_path / "ck.pt"
    save_checkpoint(model, path)
    record = torch.load(path, weights_only=True)
    mutate(record)
    torch.save(record, path)
    return path


@pytest.mark.parametrize("mutate, needle", [
    (lambda r: r["state_dict"]["w_in"].__setitem__((0, 0), float("nan")), "state_dict.w_in: contains NaN"),
    (lambda r: r["state_dict"]["w_out"].__setitem__((0, 0), float("inf")), "state_dict.w_out: contains NaN or Inf"),
    (lambda r: r["state_dict"].__setitem__("v_rec", torch.zeros(8, 5)), "state_dict"),
    (lambda r: r["state_dict"].__setitem__("w_out", torch.zeros(9, 4)), "state_dict"),
    (lambda r: r["architecture"].__setitem__("kind", "transformer"), "architecture.kind: unknown model kind"),
    (lambda r: r["architecture"].__setitem__("tau_mem", -1.0), "tau_mem"),
    (lambda r: r.__setitem__("version", 99), "version"),
])
def test_bad_checkpoints(tmp_path, capsys, mutate, needle):
    path = _checkpoint_with(tmp_path, mutate)
    code, _, err = run_cli(["compile", path, "--target", "loihi", "-o", tmp_path / "x.net"], capsys)
    assert code == 2 and needle in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "x.net").exists()


@pytest.mark.parametrize("text, needle", [
    (TH1_PARAMS.replace("tau_ratio 10\n", ""), "tau_ratio: missing key"),
    (TH1_PARAMS + "momentum 0.9\n", "momentum: unknown key"),
    (TH1_PARAMS.replace("tau_mem 0.06", "tau_mem 0"), "tau_mem: must be positive"),
])
def test_bad_parameters_file(tmp_path, capsys, authors_weights, text, needle):
    params = tmp_path / "p.txt"
    params.write_text(text)
    code, _, err = run_cli(["compile", authors_weights, "--params", params, "--target", "loihi", "-o", tmp_path / "x.net"], capsys)
    assert code == 2 and str(params) in err and needle in err, err
    assert not (tmp_path / "x.net").exists()


def test_missing_file_and_unknown_target(tmp_path, capsys, small_rsnn_checkpoint):
    code, _, err = run_cli(["compile", tmp_path / "nope.pt", "-o", tmp_path / "x.snnir"], capsys)
    assert code == 2 and "does not exist" in err
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "--target", "tpu", "-o", tmp_path / "x"], capsys)
    assert code == 2 and "unknown target" in err and not (tmp_path / "x").exists()


def test_debug_shows_the_traceback(tmp_path):
    bad = tmp_path / "r.pt"
    bad.write_bytes(b"\x00" * 64)
    res = subprocess.run(["snncc", "compile", str(bad), "-o", str(tmp_path / "x"), "--debug"], capture_output=True, text=True)
    assert res.returncode != 0 and "Traceback" in res.stderr


def test_inspect_bad_file_is_one_line(tmp_path, capsys):
    bad = tmp_path / "noise.pt"
    bad.write_bytes(os.urandom(256))
    code, out, err = run_cli(["inspect", bad, "--json"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and str(bad) in err and out == ""
