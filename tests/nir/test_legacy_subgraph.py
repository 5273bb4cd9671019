"""The NIR paper's 2023 Braille sub-graph (tests/data/nir/braille_subgraph_2023.nir) is refused in one line
naming what it lacks, and these tests show that what it lacks is what makes it the trained network.

The file (NIR repository, paper/03_rnn at a440c28) was written by hand from the trained snnTorch network
as tau_syn = 1/(1 - beta), tau_mem = 1/(1 - alpha), r = 1, w_in = 1 (NIR 0.2's writer did not store
w_in), no dt. Read as written it never spikes, at the dt the user gave (1e-4) or the one its time
constants imply (1 step per unit). Restoring snnTorch's unit gains alone gives another network;
restoring them AND exchanging tau_syn with tau_mem gives braille_zero_2023.nir (the same trained
weights, exported correctly) spike for spike. Neither the gains nor the exchange can be read from the
file. Inputs: seeded random spike trains (SYNTHETIC). ``bench/studies/legacy_subgraph.py`` prints the figures.
"""

from pathlib import Path

import h5py
import nir
import numpy as np
import pytest
from nir.serialization import hdf2dict

from nir_graphs import run_cli
from snncc.frontends import LoadOptions, load_model
from snncc.frontends.nir import graph_from_nir
from snncc.frontends.nir_legacy import LegacyFileLacks, normalise, read_legacy
from snncc.ir.liveness import population_activity

DATA = Path(__file__).resolve().parents[1] / "data" / "nir"
SUBGRAPH = DATA / "braille_subgraph_2023.nir"


def _raw():
    with h5py.File(SUBGRAPH, "r") as f:
        raw = hdf2dict(f["node"])
    normalise(raw, "", [], str(SUBGRAPH))
    raw["type_check"] = False
    return raw


def _reading(swap: bool, gains: bool, dt: float):
    """The file with NIR 0.2's lost w_in = 1 (or snnTorch's unit gains restored), taus as stored or exchanged."""
    raw = _raw()
    for lif in (raw["nodes"]["hidden"]["nodes"]["lif"], raw["nodes"]["lif2"]):
        if swap:
            lif["tau_syn"], lif["tau_mem"] = lif["tau_mem"].copy(), lif["tau_syn"].copy()
        lif["w_in"] = lif["tau_syn"].copy() if gains else np.ones_like(lif["tau_syn"])
        if gains:
            lif["r"] = lif["tau_mem"].copy()
    return graph_from_nir(nir.dict2NIRNode(raw), dt=dt, source=str(SUBGRAPH))


@pytest.fixture(scope="module")
def spikes():
    return (np.random.default_rng(0).random((8, 120, 12)) < 0.08).astype(np.uint8)


@pytest.mark.parametrize("verb", [["compile", "--target", "loihi", "-o", "X"], ["inspect"]])
def test_the_legacy_subgraph_is_refused_in_one_line_naming_what_it_lacks(verb, tmp_path, capsys):
    args = [a if a != "X" else tmp_path / "x.net" for a in verb]
    code, _, err = run_cli([args[0], SUBGRAPH, "--dt", "1e-4", *args[1:]], capsys)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1, err
    assert lines[0].startswith(f"snncc: error: {SUBGRAPH}: node 'hidden.lif'.w_in: older NIR file: this CubaLIF "
                               "stores no w_in (NIR's writer up to release 0.2 did not write it) and has r = 1"), err
    assert list(tmp_path.iterdir()) == []


def test_a_legacy_cuba_lif_that_kept_w_in_is_read_with_the_input_size_note(tmp_path):
    """The refusal is about the lost field, not the file's age: the same file with w_in stored loads."""
    with pytest.raises(LegacyFileLacks, match="stores no w_in"):
        read_legacy(SUBGRAPH)
    copy = tmp_path / "with_w_in.nir"
    copy.write_bytes(SUBGRAPH.read_bytes())
    with h5py.File(copy, "r+") as f:
        for lif in ("node/nodes/hidden/nodes/lif", "node/nodes/lif2"):
            f[lif].create_dataset("w_in", data=np.ones_like(f[lif]["tau_syn"][()]))
    g = load_model(copy, LoadOptions(dt=1.0))
    notes = g.metadata["import_notes"]
    assert any("older NIR file" in n and "read as [38]" in n for n in notes), notes   # the Input declared [12]
    assert g.node("fc1").weight.shape == (38, 12) and g.node("hidden.lin").weight.shape == (38, 38)


def test_read_as_written_it_never_spikes(spikes):
    for dt in (1e-4, 1.0):     # the dt the user gave; one step per unit, as its time constants (2 to 10) imply
        activity = population_activity(_reading(swap=False, gains=False, dt=dt), spikes)
        assert all(a.silent for a in activity.values()), activity


def test_its_gains_and_exchanged_time_constants_restore_the_trained_network(spikes):
    trained = load_model(DATA / "braille_zero_2023.nir", LoadOptions(dt=1e-4))
    from snncc.ir.simulate import simulate

    ref = simulate(trained, spikes, record="spikes")
    restored = simulate(_reading(swap=True, gains=True, dt=1.0), spikes, record="spikes")
    assert np.array_equal(np.asarray(restored.spikes["hidden.lif"]), np.asarray(ref.spikes["lif1.lif"]))
    assert np.array_equal(np.asarray(restored.spikes["lif2"]), np.asarray(ref.spikes["lif2"]))
    rates = {k: float(v.mean()) for k, v in restored.spikes.items()}
    assert 0.01 < rates["hidden.lif"] < 0.2 and 0.05 < rates["lif2"] < 0.9, rates   # alive, not saturated
    gains_only = simulate(_reading(swap=False, gains=True, dt=1.0), spikes, record="spikes")
    assert not np.array_equal(np.asarray(gains_only.spikes["hidden.lif"]), np.asarray(ref.spikes["lif1.lif"]))


def test_the_rule_is_for_older_files_only(tmp_path):
    """A CubaLIF without w_in in a file that today's nir.read takes is read as NIR says (w_in = 1)."""
    src = tmp_path / "g.nir"
    nir.write(str(src), nir.NIRGraph(
        nodes={"in": nir.Input(np.array([2])), "w": nir.Linear(weight=np.array([[0.6, 0.4]])),
               "lif": nir.CubaLIF(tau_syn=np.array([2e-3]), tau_mem=np.array([1e-2]), r=np.array([1.0]),
                                  v_leak=np.array([0.0]), v_threshold=np.array([1.0]), w_in=np.array([1.0])),
               "out": nir.Output(np.array([1]))},
        edges=[("in", "w"), ("w", "lif"), ("lif", "out")]))
    with h5py.File(src, "r+") as f:
        del f["node/nodes/lif/w_in"]
    g = load_model(src, LoadOptions(dt=1e-3))
    assert g.node("lif").n == 1 and not any("older NIR file" in n for n in g.metadata["import_notes"])
