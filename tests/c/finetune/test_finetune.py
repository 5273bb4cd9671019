"""Fine-tuning through the C target's arithmetic: the differentiable student's forward pass equals the emulator
on the integers it exports (so what trains is what runs), and ``compile --target c --finetune`` writes a checked
artefact with its record and the adapted float graph."""

from __future__ import annotations

import json

import numpy as np
import pytest

from c_test_graphs import NIR_DIR, network, random_graph, spikes


@pytest.mark.parametrize("seed,big,spikes_per_step,rule", [(0, False, 1, "per-neuron"), (1, True, 3, "per-layer-16"),
                                                           (2, False, 3, "per-layer")])
def test_student_forward_equals_the_emulator(seed, big, spikes_per_step, rule):
    import torch

    from snncc.targets.c.emulation.emulator import emulate_network
    from snncc.targets.c.finetune.student import DifferentiableC

    net = network(random_graph(seed, big=big, spikes=spikes_per_step), rule, 20)
    x = spikes(4, 20, 5, 0.3, seed)
    student = DifferentiableC(net, 20)
    with torch.no_grad():
        for w in student.w:                  # move the shadows off the grid: export must round as forward does
            w.add_(torch.as_tensor(np.random.default_rng(seed).uniform(-0.6, 0.6, tuple(w.shape))))
        run = student(torch.as_tensor(x, dtype=torch.float64))
    em = emulate_network(student.export(), x, record=True)
    for p in net.populations:
        np.testing.assert_array_equal(run.spikes[p.name].numpy(), em.spikes[p.name].astype(float))
    np.testing.assert_array_equal(run.counts.numpy(), em.counts.astype(float))


def test_student_has_gradients():
    import torch

    from snncc.targets.c.finetune.student import DifferentiableC

    net = network(random_graph(4), "per-neuron", 20)
    student = DifferentiableC(net, 20)
    run = student(torch.as_tensor(spikes(4, 20, 5, 0.3, 1), dtype=torch.float64))
    (run.counts.sum() + sum(v.sum() for v in run.voltage.values())).backward()
    assert any(w.grad is not None and w.grad.abs().sum() > 0 for w in student.w)
    assert set(student.param_groups()) == {"weights", "thresholds", "biases"}


def test_compile_finetune_writes_a_checked_artefact(tmp_path):
    from snncc.cli.main import run

    out = tmp_path / "ft_c"
    code = run(["compile", str(NIR_DIR / "braille_noDelay_noBias_subtract.nir"), "--dt", "1e-4", "--reset",
                "subtract", "--target", "c", "--rule", "per-neuron", "--time-steps", "30", "-o", str(out),
                "--finetune", "--finetune-samples", "64", "--finetune-epochs", "1", "--finetune-out",
                str(tmp_path / "adapted.nir")])
    assert code == 0
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["finetune"]["finetuned"] is True and "agreement_after" in manifest["finetune"]
    assert (tmp_path / "adapted.nir").is_file()
    from snncc.targets import get_target

    x = spikes(2, 30, 12, 0.1, 0)
    assert get_target("c").emulate(out, x).arrays()["output_spikes"].shape == (2, 30, 7)
