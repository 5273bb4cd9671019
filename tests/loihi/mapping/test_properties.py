"""Property test: on random small networks and a tiny chip (so every limit binds), the map is either
valid under an independent re-check, or refused with a message naming a limit and a layer."""

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from snncc.errors import SnnccError
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork
from snncc.targets.loihi.mapping.partition import map_network
from snncc.targets.loihi.mapping.resources import LIMIT_TITLES, ChipSpec

from .helpers import layer
from .recheck import assert_valid

TINY = ChipSpec(name="tiny", cores_per_chip=8, compartments_per_core=16, input_axons_per_core=24,
                output_axons_per_core=40, synapse_words_per_core=48, vth_profiles_per_core=2,
                compartment_profiles_per_core=3, cores_per_tile=2, mesh_tiles_ew=2, mesh_tiles_ns=2)


@st.composite
def networks(draw):
    seed = draw(st.integers(0, 2**16))
    rng = np.random.default_rng(seed)
    sizes = [draw(st.integers(1, 30))] + draw(st.lists(st.integers(1, 40), min_size=1, max_size=3))
    density = draw(st.sampled_from([1.0, 0.5, 0.15]))
    layers = [LoihiLayer("input", "input", sizes[0])]
    for i, n in enumerate(sizes[1:], start=1):
        def w(shape):
            x = (rng.integers(-100, 100, size=shape) * 2)
            x[x == 0] = 2
            x[rng.random(shape) >= density] = 0
            return x
        rec = draw(st.booleans())
        layers.append(layer(f"l{i}", n, w((n, sizes[i - 1])), kind="dense_rec" if rec else "dense",
                            w_rec=w((n, n)) if rec else None, delay=draw(st.integers(0, 3)),
                            v_th_mant=draw(st.sampled_from([50, 60, 70]))))
    return LoihiNetwork(layers, t_sample=5)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(networks())
def test_map_is_valid_or_refused_with_the_limit(net):
    try:
        cm = map_network(net, TINY)
    except SnnccError as err:
        msg = str(err)
        assert any(title in msg for title in LIMIT_TITLES.values()), msg
        assert "layer '" in msg or "core map" not in msg
        return
    d = cm.to_dict()
    assert_valid(cm.network, d, TINY)
    assert cm.lower_bound <= cm.n_cores
    assert cm.n_chips == 1 + (cm.n_cores - 1) // TINY.cores_per_chip
