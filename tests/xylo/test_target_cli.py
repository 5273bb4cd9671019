"""The registered Xylo target from the command line: compile writes the artefact directory (atomically,
byte-identical when repeated), XyloSim runs its spec.npz unchanged with the output spikes of snncc
emulate, map and report show usage and real time, and every refusal is one line, exit 2, nothing written."""

import inspect
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from snncc.ir.serialize import save_graph
from snncc.targets.xylo.spec import XyloSpec
from snncc_test_helpers import run_cli

from xylo_models import chain

QUICK = ["--calibration-samples", "12", "--time-steps", "48"]
KWARGS = ("weights_in", "weights_rec", "weights_out", "dash_mem", "dash_mem_out", "dash_syn", "dash_syn_2",
          "dash_syn_out", "threshold", "threshold_out", "bias", "bias_out", "weight_shift_in", "weight_shift_rec",
          "weight_shift_out", "aliases", "dt")


def test_compile_writes_the_artefact_directory(compiled):
    model, out, _ = compiled
    assert sorted(p.name for p in out.iterdir()) == ["README.md", "manifest.json", "run_on_board.py", "spec.npz"]
    with np.load(out / "spec.npz", allow_pickle=False) as z:
        names = sorted(k for k in z.files)
        assert names == sorted(KWARGS)
        for k in KWARGS:
            if k != "dt":
                assert np.issubdtype(z[k].dtype, np.integer), k
        assert z["weights_in"].shape[0] == 6            # one row per model input
    m = json.loads((out / "manifest.json").read_text())
    assert m["chip"]["key"] == "syns61201" and m["dt"] == pytest.approx(1e-3)
    assert m["aliases"] == [[] for _ in range(12)] and m["source"]["sha256"]
    assert m["quantization"]["rule"].startswith("single") and "candidates" in m["quantization"]
    assert "xylosim 0.1.3" in m["checked_with"]["emulator"]
    import hashlib
    for name, digest in m["files"].items():
        assert hashlib.sha256((out / name).read_bytes()).hexdigest() == digest
    assert "NOT exercised" in (out / "README.md").read_text()
    script = (out / "run_on_board.py").read_text()
    assert "NOT EXERCISED" in script and '"bias_hidden"' in script
    compile(script, "run_on_board.py", "exec")      # valid Python (not run: no board, no samna)
    assert set(KWARGS) <= set(inspect.signature(XyloSpec).parameters)


def test_compiling_again_gives_the_same_bytes_and_replaces_only_its_own_directory(compiled, tmp_path, capsys):
    model, out, _ = compiled
    again = tmp_path / "again.xylo"
    code, _, err = run_cli(["compile", model, "-o", again, "--rule", "single", *QUICK], capsys)
    assert code == 0, err
    for name in ("spec.npz", "manifest.json", "README.md", "run_on_board.py"):
        assert (again / name).read_bytes() == (out / name).read_bytes(), name
    code, _, err = run_cli(["compile", model, "-o", again, "--rule", "single", *QUICK], capsys)
    assert code == 0, err                            # an earlier snncc Xylo artefact is replaced
    user = tmp_path / "mine"
    user.mkdir()
    (user / "notes.txt").write_text("keep")
    code, out_, err = run_cli(["compile", model, "--target", "xylo", "-o", user, *QUICK], capsys)
    assert code == 2 and err.strip().startswith("snncc: error: ") and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in user.iterdir()) == ["notes.txt"] and (user / "notes.txt").read_text() == "keep"


def test_xylosim_runs_the_spec_unchanged_with_the_output_spikes_of_snncc_emulate(compiled, xylosim, tmp_path, capsys):
    _, out, x_path = compiled
    res = tmp_path / "em.npz"
    code, _, err = run_cli(["emulate", out, "--target", "xylo", "--input", x_path, "-o", res, "--record", "all"], capsys)
    assert code == 0, err
    m = json.loads((out / "manifest.json").read_text())
    pad, lag = m["feed"]["input_pad"], m["feed"]["output_lag"]
    x = np.load(x_path)
    fed = np.zeros((x.shape[0], x.shape[1] + max(pad, lag), x.shape[2]), np.uint8)
    fed[:, pad:pad + x.shape[1]] = x
    oracle = xylosim(XyloSpec.load_npz(out / "spec.npz"), out).run(fed, record=True)
    with np.load(res, allow_pickle=False) as got:
        assert got["output_spikes"].shape == (5, 40, 3)
        assert np.array_equal(got["output_spikes"], oracle.output_spikes[:, lag:lag + 40])
        assert got["output_spikes"].sum() > 0
        for name in ("vmem", "isyn", "isyn2", "spikes", "vmem_out", "isyn_out"):
            assert np.array_equal(got[name], getattr(oracle, name)[:, lag:lag + 40]), name
        assert np.array_equal(got["counts"], got["output_spikes"].sum(axis=1))


def test_stream_emulation_runs_the_samples_back_to_back(compiled, xylosim, tmp_path, capsys):
    _, out, x_path = compiled
    res = tmp_path / "stream.npz"
    code, _, err = run_cli(["emulate", out, "--target", "xylo", "--input", x_path, "-o", res, "--stream", "--gap", "7"],
                           capsys)
    assert code == 0, err
    m = json.loads((out / "manifest.json").read_text())
    pad, lag = m["feed"]["input_pad"], m["feed"]["output_lag"]
    x = np.load(x_path)
    run = np.zeros((1, pad + 5 * 47 + max(0, lag - pad), 6), np.uint8)
    for i in range(5):
        run[0, pad + 47 * i:pad + 47 * i + 40] = x[i]
    oracle = xylosim(XyloSpec.load_npz(out / "spec.npz"), out).run(run).output_spikes[0]
    with np.load(res, allow_pickle=False) as got:
        for i in range(5):
            assert np.array_equal(got["output_spikes"][i], oracle[lag + 47 * i:lag + 47 * i + 40])


def test_map_and_report_show_usage_against_each_chip_and_real_time(compiled, capsys):
    _, out, x_path = compiled
    code, text, err = run_cli(["map", out, "--target", "xylo", "--json"], capsys)
    assert code == 0, err
    d = json.loads(text)
    assert d["usage"]["syns61201"]["hidden neurons"] == {"used": 12, "limit": 1000, "fits": True}
    assert d["usage"]["syns63300"]["synaptic currents per hidden neuron"]["limit"] == 1
    rt = d["real_time"]
    assert rt["cycles_worst"] > rt["cycles_expected"] > 0 and rt["margin"] == pytest.approx(1e-3 / rt["step_time_worst_s"])
    assert "ESTIMATE" in rt["note"] and "no energy" in d["energy"]
    code, text, err = run_cli(["report", out, "--target", "xylo", "--energy", "--input", x_path, "--json"], capsys)
    assert code == 0, err
    assert "x.npy" in json.loads(text)["rates_from"]


def _refused(capsys, args, out: Path) -> str:
    code, _, err = run_cli(args, capsys)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("snncc: error: "), err
    assert not out.exists() and not list(out.parent.glob(f".{out.name}*"))
    return lines[0]


def test_design_rule_refusals_are_one_line_exit_2_nothing_written(tmp_path, capsys):
    rng = np.random.default_rng(1)
    wide = tmp_path / "wide.snnir"
    save_graph(chain(rng, n_out=9), wide)
    out = tmp_path / "o.xylo"
    line = _refused(capsys, ["compile", wide, "--target", "xylo", "-o", out, *QUICK], out)
    assert f"{wide}: " in line and "output neurons: the readout population has 9, Xylo Audio 2 has 8" in line
    many = tmp_path / "many.snnir"
    save_graph(chain(rng, n_in=17), many)
    line = _refused(capsys, ["compile", many, "--target", "xylo", "-o", out, *QUICK], out)
    assert "input channels: the model has 17, Xylo Audio 2 has 16" in line
    big = tmp_path / "big.snnir"
    save_graph(chain(rng, n_hidden=130), big)
    line = _refused(capsys, ["compile", big, "--target", "xylo", "-o", out, "--chip", "syns63300", *QUICK], out)
    assert "130" in line and "128" in line
    zero = tmp_path / "zero.snnir"
    save_graph(chain(rng, reset="zero"), zero)
    line = _refused(capsys, ["compile", zero, "--target", "xylo", "-o", out, *QUICK], out)
    assert "reset" in line and "--allow-reset-change" in line
    line = _refused(capsys, ["compile", zero, "--target", "xylo", "-o", out, "--chip", "audio9", *QUICK], out)
    assert "--chip: chip must be one of syns61201, syns63300, syns65302" in line
    line = _refused(capsys, ["compile", zero, "--target", "xylo", "-o", out, "--rule", "single", "--chip",
                             "syns63300", "--allow-reset-change", *QUICK], out)
    assert "--rule" in line and "two synaptic currents" in line


def test_the_relayed_rule_is_refused_in_one_line_where_it_cannot_fit(tmp_path, capsys):
    model = tmp_path / "m.snnir"
    save_graph(chain(np.random.default_rng(2), n_in=16, n_hidden=60), model)
    out = tmp_path / "o.xylo"
    line = _refused(capsys, ["compile", model, "--target", "xylo", "-o", out, "--rule", "relayed", "--chip",
                             "syns65302", *QUICK], out)
    assert f"{model}: --rule: the relayed rule places" in line and "128" in line
    line = _refused(capsys, ["compile", model, "--target", "xylo", "-o", out, "--rule", "relayed", "--chip",
                             "syns63300", *QUICK], out)
    assert "--rule" in line and "two synaptic currents" in line
    line = _refused(capsys, ["compile", model, "--target", "xylo", "-o", out, "--rule", "relays", *QUICK], out)
    assert "rule must be one of" in line and "relayed" in line


def test_a_changed_spec_is_refused_by_emulate(compiled, tmp_path, capsys):
    import shutil

    _, out, x_path = compiled
    copy = tmp_path / "copy.xylo"
    shutil.copytree(out, copy)
    arrays = dict(np.load(copy / "spec.npz", allow_pickle=False))
    arrays["threshold"] = arrays["threshold"] + 1
    np.savez(copy / "spec.npz", **arrays)
    line = _refused(capsys, ["emulate", copy, "--target", "xylo", "--input", x_path, "-o", tmp_path / "r.npz"],
                    tmp_path / "r.npz")
    assert "spec.npz: " in line and "SHA-256" in line


def test_the_registered_module_imports_nothing_heavy():
    code = ("import sys, json\nfrom snncc.targets import get_target\nt = get_target('xylo'); t.options_type\n"
            "print(json.dumps(sorted(m for m in ('numpy', 'torch', 'numba', 'onnx') if m in sys.modules)))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == []


def test_emulate_map_and_report_find_the_target_from_the_artefact(compiled, tmp_path, capsys):
    _, out, x_path = compiled
    code, _, err = run_cli(["emulate", out, "--input", x_path, "-o", tmp_path / "e.npz"], capsys)
    assert code == 0, err
    with np.load(tmp_path / "e.npz", allow_pickle=False) as got:
        assert got["output_spikes"].shape == (5, 40, 3)
    code, text, err = run_cli(["map", out, "--json"], capsys)
    assert code == 0 and json.loads(text)["target"] == "xylo", err
    code, text, err = run_cli(["report", out, "--energy", "--input", x_path, "--json"], capsys)
    assert code == 0 and "no energy" in json.loads(text)["energy"], err
    code, _, err = run_cli(["emulate", tmp_path / "nothing.xylo", "--input", x_path, "-o", tmp_path / "f.npz"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and not (tmp_path / "f.npz").exists()
