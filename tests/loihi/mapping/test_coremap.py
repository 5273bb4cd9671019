import json

from snncc.targets.loihi.mapping.coremap import CoreMap
from snncc.targets.loihi.mapping.partition import map_network

from .helpers import chain, paper_rsnn


def test_json_shape_and_round_trip():
    cm = map_network(paper_rsnn())
    d = json.loads(json.dumps(cm.to_dict()))
    for key in ("cores", "n_cores", "n_chips", "lower_bound", "binding_constraint", "totals", "limits"):
        assert key in d
    for c in d["cores"]:
        for key in ("core", "chip", "neurons", "input_axons", "output_axons", "synapse_bits", "layers", "percent"):
            assert key in c
        assert c["percent"]["synapse_bits"] == round(100 * c["synapse_bits"] / 1_048_576, 2)
    back = CoreMap.from_dict(d)
    assert back.to_dict() == d
    assert d["binding_constraint"] == "synapse_bits"
    assert d["totals"]["neurons"] == 478


def test_text_rendering_names_totals_and_bound(capsys):
    from rich.console import Console

    cm = map_network(paper_rsnn())
    console = Console(width=160, force_terminal=False)
    cm.render_text(console)
    out = capsys.readouterr().out
    assert "hidden[0:225]" in out and "output[0:28]" in out
    assert "lower bound 3" in out and "binding constraint: synapse memory" in out


def test_plot_writes_a_real_png(tmp_path):
    cm = map_network(chain([1000, 3000], seed=1))
    path = tmp_path / "cores.png"
    cm.plot(path)
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
    assert not list(tmp_path.glob(".*part"))          # atomic: no temporary left behind


def test_the_picture_draws_the_limit_its_title_names_and_which_population_sits_where():
    """A map bound by threshold profiles (8 per core) names that limit in the title and draws it; the lower panel
    stacks each population's neurons per core."""
    import numpy as np
    import matplotlib.pyplot as plt

    from .helpers import layer
    from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork

    rng = np.random.default_rng(0)
    n = 64
    net = LoihiNetwork([LoihiLayer("input", "input", 4),
                        layer("profiled", n, (rng.integers(1, 60, (n, 4)) * 2).astype(np.int64),
                              v_th_mant=np.arange(100, 100 + n)),        # one threshold profile per neuron
                        layer("readout", 3, (rng.integers(1, 60, (3, n)) * 2).astype(np.int64))], t_sample=10)
    cm = map_network(net)
    assert cm.binding_constraint == "vth_profiles" and "vth_profiles" in cm.drawn_limits()
    fig = cm.figure()
    top, low = fig.axes
    drawn = [t.get_text() for t in top.get_legend().get_texts()]
    assert cm.binding_constraint.replace("_", " ") in top.get_title() and "vth profiles" in drawn
    assert [t.get_text() for t in low.get_legend().get_texts()] == ["profiled", "readout"]
    heights = sum(np.array([p.get_height() for p in bars]) for bars in low.containers)
    assert heights.sum() == n + 3 and len(heights) == cm.n_cores
    plt.close(fig)
