"""Power from the Jetson's INA3221 monitor, read from sysfs every 50 ms on one rail (VDD_IN).

Two kernel layouts (``root`` is the filesystem root, an option so tests use a fake tree):

* JetPack 4.x (L4T 32, NVIDIA's iio driver), e.g. Xavier NX:
  ``sys/bus/i2c/drivers/ina3221x/7-0040/iio:device0/rail_name_<i>`` names channel i and
  ``in_power<i>_input`` is its power in mW.
* JetPack 5+ (L4T 34+, mainline hwmon driver):
  ``sys/bus/i2c/drivers/ina3221/1-0040/hwmon/hwmon<N>/in<i>_label`` names channel i,
  ``in<i>_input`` is the bus voltage in mV and ``curr<i>_input`` the current in mA;
  P [mW] = V [mV] * I [mA] / 1000.
"""

from __future__ import annotations

import glob
import os
import threading
import time
from dataclasses import dataclass, field

from snncc.targets.kit import SnnccError

DEFAULT_RAIL = "VDD_IN"
# names the main input rail has on other boards (Nano: POM_5V_IN; some docs: 5V_IN)
MAIN_RAIL_ALIASES = ("VDD_IN", "POM_5V_IN", "5V_IN")
INTERVAL_S = 0.05


@dataclass(frozen=True)
class Rail:
    name: str
    layout: str                 # "iio" (JetPack 4) | "hwmon" (JetPack 5+)
    power: str | None = None    # iio: in_power<i>_input (mW)
    voltage: str | None = None  # hwmon: in<i>_input (mV)
    current: str | None = None  # hwmon: curr<i>_input (mA)


def _read(path: str) -> str:
    with open(path, encoding="ascii") as f:
        return f.read().strip()


def list_rails(root: str = "/") -> list[Rail]:
    """Every INA3221 channel found under ``root`` (both layouts)."""
    rails: list[Rail] = []
    iio = os.path.join(root, "sys/bus/i2c/drivers/ina3221x/*/iio:device*/rail_name_*")
    for name_file in sorted(glob.glob(iio)):
        i = name_file.rsplit("_", 1)[1]
        power = os.path.join(os.path.dirname(name_file), f"in_power{i}_input")
        if os.path.exists(power):
            rails.append(Rail(_read(name_file), "iio", power=power))
    hwmon = os.path.join(root, "sys/bus/i2c/drivers/ina3221/*/hwmon/hwmon*/in*_label")
    for label_file in sorted(glob.glob(hwmon)):
        base = os.path.basename(label_file)
        i = base[2:-len("_label")]
        d = os.path.dirname(label_file)
        volt, curr = os.path.join(d, f"in{i}_input"), os.path.join(d, f"curr{i}_input")
        if i.isdigit() and os.path.exists(volt) and os.path.exists(curr):
            rails.append(Rail(_read(label_file), "hwmon", voltage=volt, current=curr))
    return rails


def find_rail(root: str = "/", name: str = DEFAULT_RAIL) -> Rail:
    """The rail called ``name`` (for the default, also its other boards' names)."""
    rails = list_rails(root)
    wanted = MAIN_RAIL_ALIASES if name == DEFAULT_RAIL else (name,)
    for want in wanted:
        for rail in rails:
            if rail.name == want:
                return rail
    found = ", ".join(sorted({r.name for r in rails})) or "none"
    raise SnnccError(f"no INA3221 rail named {name} (found: {found}); is this a Jetson? pass --power-root for a "
                     "different sysfs root", file=str(root), field="power rail")


def read_power_mw(rail: Rail) -> float:
    """Instantaneous power of ``rail`` in mW."""
    try:
        if rail.layout == "iio":
            return float(_read(rail.power))
        return float(_read(rail.voltage)) * float(_read(rail.current)) / 1000.0
    except (OSError, ValueError) as ex:
        raise SnnccError(f"cannot read the power monitor ({type(ex).__name__})", file=rail.power or rail.voltage,
                         field=rail.name) from None


@dataclass
class PowerRecord:
    rail: str
    layout: str
    interval_s: float
    samples: int
    duration_s: float
    min_mw: float
    max_mw: float
    avg_mw: float

    def energy_uj(self, seconds: float) -> float:
        """Energy over ``seconds`` at the average power: mW * s * 1000 = uJ."""
        return self.avg_mw * seconds * 1000.0


@dataclass
class PowerSampler:
    """Reads the rail every ``interval`` seconds in a background thread between start() and stop()."""

    root: str = "/"
    rail_name: str = DEFAULT_RAIL
    interval: float = INTERVAL_S
    samples: list = field(default_factory=list)   # (monotonic time, mW)

    def __post_init__(self) -> None:
        self.rail = find_rail(self.root, self.rail_name)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._error: BaseException | None = None

    def _loop(self) -> None:
        next_at = time.monotonic()
        try:
            while not self._stop.is_set():
                self.samples.append((time.monotonic(), read_power_mw(self.rail)))
                next_at += self.interval
                self._stop.wait(max(0.0, next_at - time.monotonic()))
        except BaseException as ex:  # reported by stop()
            self._error = ex

    def start(self) -> "PowerSampler":
        self.samples = []
        self._stop.clear()
        self._t0 = time.monotonic()
        self._thread = threading.Thread(target=self._loop, name="ina3221-sampler", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> PowerRecord:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        duration = time.monotonic() - self._t0
        if self._error is not None:
            raise self._error
        if not self.samples:
            self.samples.append((time.monotonic(), read_power_mw(self.rail)))
        values = [p for _, p in self.samples]
        return PowerRecord(self.rail.name, self.rail.layout, self.interval, len(values), duration,
                           min(values), max(values), sum(values) / len(values))

    def __enter__(self) -> "PowerSampler":
        return self.start()

    def __exit__(self, *exc) -> None:
        if self._thread is not None and not self._stop.is_set():
            self._stop.set()
            self._thread.join()
