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


def _zip_with_a_bad_utf8_name(path, member_bytes: bytes) -> None:
    """A zip whose member name is flagged UTF-8 (bit 11) but holds bytes that are not UTF-8 (what a fuzzed byte
    in a torch archive's central directory once made: zipfile raises UnicodeDecodeError, not BadZipFile)."""
    import zipfile

    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("archive/\u00e9data.pkl", member_bytes)
    raw = path.read_bytes()
    assert raw.count("\u00e9".encode()) == 2        # the local header and the central directory
    path.write_bytes(raw.replace("\u00e9".encode(), b"\xa5\xa5"))


def test_a_torch_archive_with_a_name_that_is_not_utf8_is_one_line(tmp_path):
    import pytest

    p = tmp_path / "m.pt"
    _zip_with_a_bad_utf8_name(p, b"\x80\x02}q\x00.")
    with pytest.raises(SnnccError, match="damaged zip archive"):
        load_model(p, LoadOptions())


def test_an_input_npz_with_a_damaged_member_is_one_line(tmp_path):
    import io
    import zipfile

    import pytest

    from snncc.inputs import load_array

    bad_name = tmp_path / "names.npz"
    buf = io.BytesIO()
    np.save(buf, np.zeros((2, 3, 4), np.uint8))
    _zip_with_a_bad_utf8_name(bad_name, buf.getvalue())
    crc = tmp_path / "crc.npz"
    np.savez_compressed(crc, inputs=np.arange(4096, dtype=np.int64).reshape(8, 16, 32) % 7)
    raw = bytearray(crc.read_bytes())
    with zipfile.ZipFile(crc) as zf:
        start = zf.getinfo("inputs.npy").header_offset + 30 + len("inputs.npy")   # the compressed bytes
    for at in range(start + 40, start + 60):
        raw[at] ^= 0x5A
    crc.write_bytes(bytes(raw))
    for path in (bad_name, crc):
        with pytest.raises(SnnccError, match="not a readable .npy/.npz array"):
            load_array(path)


def test_a_data_set_with_a_damaged_member_is_one_line(tmp_path):
    import zipfile

    import pytest

    from snncc.data.dataset_file import load_dataset

    p = tmp_path / "d.npz"
    np.savez_compressed(p, inputs=np.arange(4096, dtype=np.int64).reshape(8, 16, 32) % 7, labels=np.zeros(8, np.int64),
                        meta=np.array("{}"))
    raw = bytearray(p.read_bytes())
    with zipfile.ZipFile(p) as zf:
        start = zf.getinfo("inputs.npy").header_offset + 30 + len("inputs.npy")
    for at in range(start + 40, start + 60):
        raw[at] ^= 0x5A
    p.write_bytes(bytes(raw))
    with pytest.raises(SnnccError, match="not a readable .npz data set"):
        load_dataset(p)
