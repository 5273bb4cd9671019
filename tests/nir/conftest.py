import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

CNN = Path(__file__).resolve().parents[1] / "data" / "nir" / "cnn_sinabs.nir"


@pytest.fixture(scope="session")
def cnn_loihi_bundle(tmp_path_factory):
    """cnn_sinabs.nir compiled for Loihi at 12 steps (``snncc compile ... --time-steps 12 --json``) once per
    session, not once per test (a few seconds each): a function of the calling test's ``capsys`` that returns
    (the bundle's path, compile's JSON report). Tests read the bundle and write their outputs elsewhere."""
    from snncc_test_helpers import run_cli

    made = {}

    def compiled(capsys):
        if not made:
            out = tmp_path_factory.mktemp("cnn_loihi") / "cnn.net"
            code, stdout, err = run_cli(["compile", CNN, "--target", "loihi", "-o", out, "--time-steps", "12",
                                         "--json"], capsys)
            assert code == 0, err
            made["bundle"] = (out, json.loads(stdout))
        return made["bundle"]
    return compiled
