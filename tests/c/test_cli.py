"""The C target from the command line: compile, emulate, run (host and QEMU), check, map, report; what it
refuses, in one line with exit status 2."""

from __future__ import annotations

import json

import numpy as np
import pytest

from c_test_graphs import NIR_DIR, need


def cli(args: list[str]) -> tuple[int, str, str]:
    import contextlib
    import io

    from snncc.cli.main import run

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = run(args)
    return code, out.getvalue(), err.getvalue()


def test_compile_writes_the_artefact(braille_artefact):
    names = sorted(p.name for p in braille_artefact.iterdir())
    assert names == sorted(["Makefile", "README.md", "main.c", "manifest.json", "mps2_an386.ld", "network.npz",
                            "snn.c", "snn.cmake", "snn.h", "startup_mps2.c"])
    manifest = json.loads((braille_artefact / "manifest.json").read_text())
    assert manifest["format"] == "snncc-c-artefact"
    assert manifest["model"]["resets"] == {"lif1.lif": "subtract", "lif2": "subtract"}   # subtract stays subtract
    assert manifest["selection"]["rule"] == manifest["arithmetic"]["rule"]
    assert set(manifest["selection"]["candidates"]) == {"per-layer", "per-neuron", "per-layer-16", "per-neuron-16"}
    source = (braille_artefact / "snn.c").read_text()
    assert "float" not in source and "double" not in source and "malloc" not in source
    includes = sorted({line.split()[1] for line in source.splitlines() + (braille_artefact / "snn.h").read_text()
                       .splitlines() if line.startswith("#include")})
    assert includes == ['"snn.h"', "<stdint.h>", "<string.h>"]
    assert "static const int" in source


def test_identify_returns_the_model_record(braille_artefact):
    from snncc.targets import get_target

    found = get_target("c").identify(braille_artefact)
    assert found is not None and found.target == "c" and found.model["graph_sha256"]
    assert "manifest.json" in found.files and "snn.c" in found.files


def test_emulate_and_run_host_write_the_same_arrays(braille_artefact, tmp_path):
    need("gcc")
    x = (np.random.default_rng(0).random((5, 50, 12)) < 0.1).astype(np.uint8)
    np.save(tmp_path / "x.npy", x)
    code, out, err = cli(["emulate", str(braille_artefact), "--input", str(tmp_path / "x.npy"), "-o",
                          str(tmp_path / "e.npz")])
    assert code == 0, err
    code, out, err = cli(["run", str(braille_artefact), "--target", "c", "--input", str(tmp_path / "x.npy"),
                          "--backend", "host", "-o", str(tmp_path / "h.npz")])
    assert code == 0, err
    e, h = np.load(tmp_path / "e.npz"), np.load(tmp_path / "h.npz")
    assert sorted(e.files) == sorted(h.files) == ["counts", "output_spikes", "prediction"]
    for key in e.files:
        np.testing.assert_array_equal(e[key], h[key])
    code, _, err = cli(["emulate", str(braille_artefact), "--input", str(tmp_path / "x.npy"), "-o",
                        str(tmp_path / "all.npz"), "--record", "all"])
    assert code == 0, err
    assert {"lif1.lif_voltage", "lif2_current", "lif2_spikes"} <= set(np.load(tmp_path / "all.npz").files)


def test_run_qemu_and_stream_mode(braille_artefact, tmp_path):
    need("arm-none-eabi-gcc", "qemu-system-arm")
    from snncc.targets import get_target

    x = (np.random.default_rng(1).random((3, 50, 12)) < 0.1).astype(np.uint8)
    target = get_target("c")
    for stream in (False, True):
        emulated = target.emulate(braille_artefact, x, stream=stream)
        ran = target.run(braille_artefact, x, backend="qemu", stream=stream)
        np.testing.assert_array_equal(ran.arrays()["output_spikes"], emulated.arrays()["output_spikes"])
        assert ran.as_dict()["timing"]["instructions_per_step"] > 0


def test_check_reports_stages_and_causes(braille_artefact):
    code, out, err = cli(["check", str(NIR_DIR / "braille_noDelay_noBias_subtract.nir"), "--dt", "1e-4", "--reset",
                          "subtract", "--artefact", str(braille_artefact), "--samples", "200", "--json"])
    assert code == 0, err
    record = json.loads(out)
    assert record["target"] == "c" and record["samples"] == 200 and record["steps"] == 50
    assert [s["key"] for s in record["stages"]] == ["weights", "decays", "grid", "artefact"]
    assert record["causes"]["reset"] is None and record["causes"]["timing"] is None
    assert record["causes"]["saturation"] is not None
    assert record["ceiling"]["noise"] == 0.01
    assert record["argmax_agreement"] >= 0.9


def test_check_compiles_when_no_artefact_is_given():
    code, out, err = cli(["check", str(NIR_DIR / "braille_zero_2023.nir"), "--dt", "1e-4", "--target", "c",
                          "--rule", "per-neuron", "--time-steps", "40", "--samples", "64"])
    assert code == 0, err
    assert "compiled here exactly as `snncc compile` would" in out and "loss by cause" in out


def test_map_and_report(braille_artefact, tmp_path):
    code, out, err = cli(["map", str(braille_artefact), "--json"])
    assert code == 0, err
    record = json.loads(out)
    assert record["mcu"] == "stm32l431rc" and record["memory"]["ram_state_bytes"] > 0
    # another part: chosen when the model is compiled (map compiles a model file first); on an artefact it is fixed
    code, out, err = cli(["map", str(NIR_DIR / "braille_noDelay_noBias_subtract.nir"), "--target", "c", "--dt", "1e-4",
                          "--reset", "subtract", "--time-steps", "20", "--rule", "per-neuron", "--mcu", "stm32l031k6",
                          "--json"])
    assert code == 0, err
    record = json.loads(out)
    assert record["mcu"] == "stm32l031k6" and record["fit"]["ram_limit"] == 8 * 1024
    code, out, err = cli(["map", str(braille_artefact), "--mcu", "stm32l031k6"])
    assert code == 2 and ": --mcu: " in err
    code, out, err = cli(["map", str(braille_artefact), "--plot", str(tmp_path / "m.png")])
    assert code == 0 and (tmp_path / "m.png").is_file()
    code, out, err = cli(["report", str(braille_artefact), "--energy", "--samples", "4", "--rate", "0.08", "--json"])
    assert code == 0, err
    record = json.loads(out)
    assert record["event_rates"]
    if record["timing"] is not None:
        t = record["timing"]
        assert t["cycles_per_step"] == pytest.approx(t["instructions_per_step"] * t["cpi_assumed"])
        assert t["cycle_budget_per_step"] == pytest.approx(80e6 * 1e-4)


@pytest.mark.parametrize("args,field", [
    (["--rule", "int4"], "--rule"),
    (["--mcu", "pdp11"], "--mcu"),
    (["--scale", "global"], "--scale"),
])
def test_bad_options_are_refused_in_one_line(tmp_path, args, field):
    code, out, err = cli(["compile", str(NIR_DIR / "lif_norse.nir"), "--dt", "1e-4", "--target", "c", "-o",
                          str(tmp_path / "o"), *args])
    line = err.strip().splitlines()[-1]
    assert code == 2 and line.startswith("snncc: error: ") and f": {field}: " in line
    assert not (tmp_path / "o").exists()


def test_a_graph_the_target_cannot_express_is_refused_naming_the_node(tmp_path):
    from snncc.ir.graph import Graph
    from snncc.ir.nodes import LIF, Dense, Input, Output, Readout
    from snncc.ir.serialize import save_graph

    g = Graph(dt=1e-3, name="membrane")
    g.add("input", Input(width=2))
    g.add("w", Dense(weight=np.ones((2, 2))))
    g.add("li", LIF(n=2, tau_syn=0.01, tau_mem=0.01, threshold=1.0))
    g.add("readout", Readout(width=2, mode="membrane_max"))
    g.add("output", Output(width=2))
    for u, v in (("input", "w"), ("w", "li"), ("li", "readout"), ("readout", "output")):
        g.connect(u, v)
    save_graph(g, tmp_path / "m.snnir")
    code, out, err = cli(["compile", str(tmp_path / "m.snnir"), "--target", "c", "-o", str(tmp_path / "o")])
    line = err.strip().splitlines()[-1]
    assert code == 2 and line.startswith("snncc: error: ")
    assert "node 'readout'" in line and "spike counts" in line


def test_a_changed_file_is_refused(braille_artefact, tmp_path):
    import shutil

    copy = tmp_path / "changed"
    shutil.copytree(braille_artefact, copy)
    (copy / "snn.c").write_text((copy / "snn.c").read_text().replace("(int32_t)", "(int32_t) "))
    np.save(tmp_path / "x.npy", np.zeros((1, 5, 12), np.uint8))
    code, out, err = cli(["emulate", str(copy), "--input", str(tmp_path / "x.npy"), "-o", str(tmp_path / "e.npz")])
    assert code == 2 and "snn.c" in err and "SHA-256" in err


def test_the_nir_graph_no_target_can_read_is_refused_in_one_line(tmp_path):
    """braille_subgraph_2023.nir (an older NIR writer's sub-graph) is refused by the frontend, for this target too."""
    code, out, err = cli(["compile", str(NIR_DIR / "braille_subgraph_2023.nir"), "--dt", "1e-4", "--target", "c", "-o",
                          str(tmp_path / "o")])
    lines = err.strip().splitlines()
    assert code == 2 and lines[-1].startswith("snncc: error: ")
    assert all(ln.startswith("snncc: note") or ln.startswith("snncc: progress") for ln in lines[:-1])
