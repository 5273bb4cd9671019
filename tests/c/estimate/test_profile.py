"""``profile`` (``snncc compare``'s hardware columns): resources against the part, real time and energy from the
instructions QEMU counts (ESTIMATE), NeuroBench's metrics from the artefact's own synapses and emulation."""

from __future__ import annotations

from c_test_graphs import NIR_DIR, need, spikes


def test_profile_of_the_braille_artefact(braille_artefact):
    need("arm-none-eabi-gcc", "qemu-system-arm")
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets import get_target

    graph = load_model(NIR_DIR / "braille_noDelay_noBias_subtract.nir", LoadOptions(dt=1e-4, reset="subtract"))
    record = get_target("c").profile(graph, braille_artefact, spikes(16, 50, 12, 0.08, 0)).as_dict()
    assert record["target"] == "c"
    what = {r["what"].split(" (")[0]: r for r in record["resources"]}
    assert what["RAM"]["limit"] == 64 * 1024 and what["neurons"]["used"] == 47
    assert record["real_time"]["margin"] > 1 and record["real_time"]["basis"].startswith("ESTIMATE")
    assert record["energy"]["uj_per_sample"] > 0 and "DS11453" in record["energy"]["source"]
    nb = record["neurobench"]
    assert nb["synaptic_operations"]["Effective_ACs"] > 0 and 0 < nb["activation_sparsity"] < 1
