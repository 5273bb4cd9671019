"""The INA3221 sampler against fake sysfs trees in both kernel layouts (JetPack 4 iio, JetPack 5+ hwmon)."""

from __future__ import annotations

import time

import pytest

from snncc.errors import SnnccError
from snncc.targets.jetson.power import PowerSampler, find_rail, list_rails, read_power_mw

XAVIER_NX_RAILS = ("VDD_IN", "VDD_CPU_GPU_CV", "VDD_SOC")


def make_iio_tree(root, power_mw=(3851, 3900), device="7-0040"):
    """JetPack 4.6 Xavier NX: .../ina3221x/7-0040/iio:device0/{rail_name_i, in_power<i>_input (mW)}."""
    d = root / f"sys/bus/i2c/drivers/ina3221x/{device}/iio:device0"
    d.mkdir(parents=True)
    for i, name in enumerate(XAVIER_NX_RAILS):
        (d / f"rail_name_{i}").write_text(name + "\n")
        (d / f"in_power{i}_input").write_text(f"{power_mw[0] if i == 0 else 500}\n")
        (d / f"in_current{i}_input").write_text("700\n")
        (d / f"in_voltage{i}_input").write_text("5000\n")
    return d / "in_power0_input"


def make_hwmon_tree(root, millivolts=5000, milliamps=800):
    """JetPack 5+: .../ina3221/1-0040/hwmon/hwmon3/{in<i>_label, in<i>_input (mV), curr<i>_input (mA)}."""
    d = root / "sys/bus/i2c/drivers/ina3221/1-0040/hwmon/hwmon3"
    d.mkdir(parents=True)
    for i, name in enumerate(XAVIER_NX_RAILS, start=1):
        (d / f"in{i}_label").write_text(name + "\n")
        (d / f"in{i}_input").write_text(f"{millivolts}\n")
        (d / f"curr{i}_input").write_text(f"{milliamps if i == 1 else 100}\n")
    (d / "in7_label").write_text("sum of shunt voltages\n")  # no in7 current: ignored
    (d / "in7_input").write_text("12\n")
    return d


def test_jetpack4_iio_layout(tmp_path):
    make_iio_tree(tmp_path, power_mw=[3851])
    assert [r.name for r in list_rails(str(tmp_path))] == list(XAVIER_NX_RAILS)
    rail = find_rail(str(tmp_path))
    assert rail.layout == "iio" and rail.name == "VDD_IN"
    assert read_power_mw(rail) == 3851.0


def test_jetpack5_hwmon_layout_computes_power(tmp_path):
    make_hwmon_tree(tmp_path, millivolts=5000, milliamps=800)
    rail = find_rail(str(tmp_path))
    assert rail.layout == "hwmon"
    assert read_power_mw(rail) == pytest.approx(4000.0)  # 5000 mV * 800 mA / 1000
    assert read_power_mw(find_rail(str(tmp_path), "VDD_SOC")) == pytest.approx(500.0)


def test_nano_main_rail_alias(tmp_path):
    d = tmp_path / "sys/bus/i2c/drivers/ina3221x/6-0040/iio:device0"
    d.mkdir(parents=True)
    (d / "rail_name_0").write_text("POM_5V_IN\n")
    (d / "in_power0_input").write_text("2500\n")
    assert find_rail(str(tmp_path)).name == "POM_5V_IN"


def test_no_monitor_is_one_clear_error(tmp_path):
    with pytest.raises(SnnccError, match="no INA3221 rail named VDD_IN"):
        find_rail(str(tmp_path))
    make_iio_tree(tmp_path)
    with pytest.raises(SnnccError, match="found: VDD_CPU_GPU_CV, VDD_IN, VDD_SOC"):
        find_rail(str(tmp_path), "GPU")


def test_sampler_reads_every_50_ms_and_summarises(tmp_path):
    power_file = make_iio_tree(tmp_path, power_mw=[3000])
    sampler = PowerSampler(root=str(tmp_path))
    sampler.start()
    time.sleep(0.12)
    power_file.write_text("5000\n")  # the load rises mid-run
    time.sleep(0.2)
    rec = sampler.stop()
    assert rec.interval_s == 0.05 and rec.rail == "VDD_IN"
    assert 4 <= rec.samples <= 9, rec.samples  # ~0.32 s / 50 ms, with slack for a busy machine
    assert rec.min_mw == 3000 and rec.max_mw == 5000 and 3000 < rec.avg_mw < 5000
    times = [t for t, _ in sampler.samples]
    gaps = [b - a for a, b in zip(times, times[1:])]
    assert all(0.03 < g < 0.2 for g in gaps), gaps
    assert rec.energy_uj(0.01) == pytest.approx(rec.avg_mw * 10.0)  # mW * 10 ms = uJ * 10


def test_sampler_reports_an_unreadable_monitor(tmp_path):
    power_file = make_iio_tree(tmp_path)
    sampler = PowerSampler(root=str(tmp_path)).start()
    power_file.write_text("not a number\n")
    time.sleep(0.12)
    with pytest.raises(SnnccError, match="cannot read the power monitor"):
        sampler.stop()
