"""Fuzzing the loaders: random and mutated files end in SnnccError, never another exception."""


import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from snncc.errors import SnnccError
from snncc.frontends import LoadOptions, load_model
from snncc.frontends.checkpoint import save_checkpoint
from snncc.frontends.params import parse_params
from snncc.ir import save_graph
from snncc.frontends.builders import snn_graph
from snncc.models import SNNConfig, SpikingClassifier

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def _valid_bytes(kind, tmp_path) -> bytes:
    if kind == "checkpoint":
        p = tmp_path / "ck.pt"
        save_checkpoint(SpikingClassifier(SNNConfig(n_hidden=4, n_outputs=3, n_inputs=2)), p)
    else:
        p = tmp_path / "g.snnir"
        rng = np.random.default_rng(0)
        save_graph(snn_graph(rng.normal(size=(2, 4)), rng.normal(size=(4, 3)), None, dt=0.005, tau_syn=0.006, tau_mem=0.06), p)
    return p.read_bytes()


def _try_load(path):
    try:
        load_model(path, LoadOptions())
    except SnnccError:
        pass


@SETTINGS
@given(data=st.binary(min_size=0, max_size=2048), suffix=st.sampled_from([".pt", ".snnir", ".pth"]))
def test_random_bytes(tmp_path, data, suffix):
    p = tmp_path / f"f{suffix}"
    p.write_bytes(data)
    _try_load(p)


@SETTINGS
@given(kind=st.sampled_from(["checkpoint", "snnir"]), cut=st.floats(0, 1), flips=st.lists(st.tuples(st.floats(0, 1), st.integers(0, 255)), max_size=8))
def test_mutated_valid_files(tmp_path, kind, cut, flips):
    data = bytearray(_valid_bytes(kind, tmp_path))
    for where, value in flips:
        data[int(where * (len(data) - 1))] = value
    data = bytes(data[: max(1, int(cut * len(data)))]) if cut < 0.999 else bytes(data)
    p = tmp_path / ("m.pt" if kind == "checkpoint" else "m.snnir")
    p.write_bytes(data)
    _try_load(p)


@SETTINGS
@given(text=st.text(max_size=400))
def test_params_parser(text):
    try:
        parse_params(text)
    except SnnccError:
        pass
