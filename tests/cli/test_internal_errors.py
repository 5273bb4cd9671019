"""A check of snncc's own work that fails is a bug: one ``snncc: internal error:`` line and status 1.

``snncc.errors.InternalError`` is deliberately not a ``SnnccError``: handlers meant for bad input
(a scale candidate that cannot be lowered, a loader trying another format) must not swallow it.
"""

from pathlib import Path

import pytest

from snncc.errors import InternalError, SnnccError
from snncc_test_helpers import run_cli

DATA = Path(__file__).resolve().parents[1] / "data" / "nir"


def test_internal_error_is_not_a_user_error():
    assert not issubclass(InternalError, SnnccError)
    assert InternalError("check failed: x", field="timing").line() == "timing: check failed: x"


def test_a_failing_lowering_check_ends_with_one_internal_error_line_and_status_1(tmp_path, capsys, monkeypatch):
    """Put the old timing bug back (a voltage bias left in the compartment of a late population): the
    compile's own float check catches it, and the CLI reports a bug, not bad input."""
    import snncc.targets.loihi.lowering.timing as timing

    monkeypatch.setattr(timing, "_late_voltage_biases", lambda graph, shift: [])
    out = tmp_path / "x.net"
    code, _, err = run_cli(["compile", DATA / "two_lif_neurons.nir", "--dt", "1e-3", "--target", "loihi",
                            "-o", out], capsys)
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("snncc: note:")]
    assert code == 1 and len(lines) == 1, err
    assert lines[0].startswith("snncc: internal error: timing: check failed: the lowered timing does not "
                               "reproduce the IR in float (layer 'lif1' first differs at step "), err
    assert "Traceback" not in err and not out.exists()


def test_debug_shows_the_traceback_of_an_internal_error(tmp_path, capsys, monkeypatch):
    import snncc.targets.loihi.lowering.timing as timing

    monkeypatch.setattr(timing, "_late_voltage_biases", lambda graph, shift: [])
    with pytest.raises(InternalError, match=r"first differs at step \d+"):
        run_cli(["compile", DATA / "two_lif_neurons.nir", "--dt", "1e-3", "--target", "loihi",
                 "-o", tmp_path / "x.net", "--debug"], capsys)


def test_the_auto_scale_rule_does_not_swallow_an_internal_error():
    """``scaling.choose`` leaves out candidates that raise SnnccError (cannot be lowered); a bug must pass."""
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets.loihi.lowering import scaling

    g = load_model(DATA / "braille_zero_2023.nir", LoadOptions(dt=1e-4))   # outliers: auto measures candidates

    def broken(gq, rq):
        raise InternalError("check failed: a broken measurement", field="scale")

    with pytest.raises(InternalError, match="a broken measurement"):
        scaling.choose(g, "auto", broken, "test inputs")
