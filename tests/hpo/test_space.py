"""The search space: ranges stated once, --range overrides checked, step 2's grid."""

from __future__ import annotations

import pytest

from snncc.errors import SnnccError
from snncc.hpo.outcome import parse_objectives
from snncc.hpo.space import SEARCH_SPACE, grid_around, preset_in_space, search_space
from snncc.training.presets import PRESETS


def test_the_space_brackets_every_paper_preset():
    for th, p in PRESETS.items():
        assert preset_in_space(th, SEARCH_SPACE) == p.as_dict()


def test_range_overrides_and_fixing_a_value():
    space = search_space(["tau_mem=0.02:0.1", "tau_ratio=10"])
    assert (space["tau_mem"].low, space["tau_mem"].high, space["tau_mem"].log) == (0.02, 0.1, True)
    assert space["tau_ratio"].fixed
    assert preset_in_space(1, search_space(["tau_mem=0.07:0.1"])) is None   # th1's 0.06 is outside


@pytest.mark.parametrize("item", ["tau_mem=0.1:0.02", "tau_mem=x:1", "nope=1:2", "tau_mem", "scale=0:5",
                                  "nb_input_copies=1.5:4", "reg_spikes=-1:1", "tau_mem=1:inf"])
def test_bad_ranges_are_one_line_errors(item):
    with pytest.raises(SnnccError) as ex:
        search_space([item])
    assert "--range" in ex.value.line() and "\n" not in ex.value.line()


def test_a_range_given_twice_is_refused():
    with pytest.raises(SnnccError):
        search_space(["tau_mem=0.02:0.1", "tau_mem=0.03:0.1"])


def test_grid_around_the_best():
    g = grid_around({"time_bin_size": 5, "nb_input_copies": 4}, SEARCH_SPACE, span=1)
    assert g == {"time_bin_size": [4, 5, 6], "nb_input_copies": [3, 4, 6]}
    g = grid_around({"time_bin_size": 2, "nb_input_copies": 16}, SEARCH_SPACE, span=1)
    assert g == {"time_bin_size": [2, 3], "nb_input_copies": [12, 16]}     # clipped at the range's ends
    g = grid_around({"time_bin_size": 5, "nb_input_copies": 5}, SEARCH_SPACE, span=2)
    assert g["nb_input_copies"] == [3, 4, 5, 6, 8]                          # off-ladder best joins the ladder


def test_objectives():
    assert parse_objectives("pareto") == ("accuracy", "energy", "cores")
    assert parse_objectives("accuracy, delay") == ("accuracy", "delay")
    for bad in ("speed", "accuracy,accuracy", ""):
        with pytest.raises(SnnccError):
            parse_objectives(bad)
