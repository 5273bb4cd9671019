"""``snncc map`` and ``snncc report --energy`` of a C artefact.

    map       flash and RAM against a part (``--mcu``, default the one compile recorded): the constant data and
              the state counted exactly from the artefact, the code measured with arm-none-eabi-gcc where it is
              installed (``memory.py``)
    report    the same, plus event rates measured in the emulator on the inputs, instructions per step counted
              in QEMU on the same inputs (where arm-none-eabi-gcc and qemu-system-arm are installed), and from
              them time, real-time verdict and energy per step and per sample: ESTIMATES (``realtime.py``)
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from snncc.targets.c.estimate.memory import fit, memory_record
from snncc.targets.c.estimate.parts import PARTS


def measured_code(path: Path) -> dict[str, int] | None:
    """text/data/bss of snn.c built for a Cortex-M4 (-Os), or None without arm-none-eabi-gcc."""
    from snncc.targets.c.toolchain import build as tb
    from snncc.targets.c.toolchain import commands as cmd

    if not (tb.available(cmd.ARM_CC) and tb.available(cmd.ARM_SIZE)):
        return None
    command = [cmd.ARM_CC, *cmd.M4_FLAGS, "-c", "-o", "snn_m4.o", "snn.c"]
    with tempfile.TemporaryDirectory(prefix="snncc-c-size-") as tmp:
        built = tb.build(tb.artefact_sources(path), command, "snn_m4.o", workdir=Path(tmp))
        return tb.section_sizes(built.path)


@dataclass
class CUsage:
    """The artefact on a part: memory (map), and with ``timing`` the real-time and energy ESTIMATE (report)."""

    artefact: str
    sha256: str
    part_key: str
    memory: dict[str, Any]
    fit: dict[str, Any]
    code: dict[str, int] | None
    populations: list[dict[str, Any]]
    timing: dict[str, Any] | None = None
    rates: dict[str, float] = field(default_factory=dict)
    inputs: str = ""
    notes: list[str] = field(default_factory=list)
    source: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"target": "c", "artefact": self.artefact, "sha256": self.sha256, "mcu": self.part_key,
                "memory": self.memory, "fit": self.fit, "code": self.code, "populations": self.populations,
                "timing": self.timing, "event_rates": self.rates, "inputs": self.inputs, "notes": self.notes}

    def as_dict(self) -> dict[str, Any]:
        return self.to_dict()

    def lines(self) -> list[str]:
        f = self.fit
        out = [f"C artefact {self.artefact} (SHA-256 {self.sha256[:16]}...) on {f['part']}",
               f"  flash {f['flash_bytes']:,} / {f['flash_limit']:,} bytes ({100 * f['flash_share']:.1f} %; "
               f"{f['flash_counted']}); weights {self.memory['flash_weights_bytes']:,} bytes",
               f"  RAM   {f['ram_bytes']:,} / {f['ram_limit']:,} bytes ({100 * f['ram_share']:.1f} %; "
               f"sizeof(snn_state_t)) -> {'fits' if f['fits'] else 'DOES NOT FIT'}",
               f"  part figures: {f['source']}"]
        if self.rates:
            out.append("  event rates (spikes per neuron and step, emulator): "
                       + ", ".join(f"{k} {v:.4f}" for k, v in self.rates.items()))
        t = self.timing
        if t is not None:
            verdict = "REAL TIME" if t["real_time"] else "NOT real time"
            out += [f"  {t['instructions_per_step']:.0f} instructions per step on average, at most "
                    f"{t['most_instructions_in_a_step']} (counted in QEMU on {self.inputs})",
                    f"  ESTIMATE at CPI {t['cpi_assumed']}: {t['cycles_per_step']:.0f} cycles per step "
                    f"({1e6 * t['time_per_step_s']:.1f} us at {t['clock_hz'] / 1e6:g} MHz) against "
                    f"{t['cycle_budget_per_step']:.0f} in dt = {t['dt_s']:g} s: {verdict}, margin "
                    f"{100 * t['margin']:.0f} %; worst step {t['worst_step_cycles']:.0f} cycles",
                    f"  ESTIMATE energy: {1e6 * t['energy_per_step_j']:.3f} uJ per step, "
                    f"{1e6 * t['energy_per_sample_j']:.1f} uJ per sample of {t['steps_per_sample']} steps "
                    f"({t['run_ua_per_mhz']:g} uA/MHz x {t['supply_volts']:g} V)"]
            if t.get("note"):
                out.append(f"  note: {t['note']}")
        out += [f"  note: {n}" for n in self.notes]
        return out

    def render_text(self, console: Any) -> None:
        for line in self.lines():
            console.print(line, markup=False, highlight=False, soft_wrap=True)

    def plot(self, path: str | Path) -> Path:
        """Flash and RAM as shares of the part's, a PNG written atomically."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from snncc.targets.kit.writing import atomic_path

        f = self.fit
        fig, ax = plt.subplots(figsize=(5, 2.4))
        ax.barh(["flash", "RAM"], [100 * f["flash_share"], 100 * f["ram_share"]], color=["#4878a8", "#a86848"])
        ax.axvline(100, color="k", lw=1)
        ax.set_xlabel(f"% of {f['part']}")
        fig.tight_layout()
        with atomic_path(Path(path)) as tmp:
            fig.savefig(tmp, format="png", dpi=100)
        plt.close(fig)
        return Path(path)


def usage_of_artefact(path: str | Path, part_key: str | None = None) -> CUsage:
    """``map``: the artefact at ``path`` on ``part_key`` (default: the part compile recorded)."""
    from snncc.targets.c.artefact.written import open_artefact

    written = open_artefact(path)
    key = part_key or written.manifest.get("part", {}).get("key") or "stm32l431rc"
    source = (Path(path) / "snn.c").read_text(encoding="utf-8")
    memory = memory_record(written.network, source)
    code = measured_code(Path(path))
    flash = None if code is None else code["text"] + code["data"]
    pops = [{"name": p.name, "n": p.n, "reset": p.reset, "frac_bits": p.frac_bits} for p in written.network.populations]
    usage = CUsage(str(path), written.sha256, key, memory, fit(memory, PARTS[key], flash), code, pops)
    if code is None:
        usage.notes.append("code size not measured: arm-none-eabi-gcc is not installed")
    return usage


def estimate_artefact(path: str | Path, x: np.ndarray, what: str, part_key: str | None = None) -> CUsage:
    """``report --energy``: ``usage_of_artefact`` plus event rates and counted instructions on ``x``."""
    from snncc.targets.c.artefact.written import open_artefact
    from snncc.targets.c.emulation.emulator import emulate_network
    from snncc.targets.c.estimate.realtime import realtime_record
    from snncc.targets.c.toolchain import build as tb
    from snncc.targets.c.toolchain import commands as cmd

    usage = usage_of_artefact(path, part_key)
    written = open_artefact(path)
    net = written.network
    run = emulate_network(net, x, populations=tuple(p.name for p in net.populations))
    usage.rates = {k: float(v.mean()) for k, v in run.spikes.items()}
    usage.inputs = what
    if not (tb.available(cmd.ARM_CC) and tb.available(cmd.QEMU)):
        usage.notes.append("instructions not counted: arm-none-eabi-gcc and qemu-system-arm are needed "
                           "(Debian: gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm)")
        return usage
    with tempfile.TemporaryDirectory(prefix="snncc-c-report-") as tmp:
        built = tb.build(tb.artefact_sources(Path(path)), cmd.m4_command(), cmd.M4_PROGRAM, workdir=Path(tmp))
        ran = tb.run_qemu(built.path, x, net.outputs)
    if not np.array_equal(ran.output_spikes, run.output_spikes):
        from snncc.targets.kit import InternalError

        raise InternalError("the Cortex-M4 build in QEMU and the emulator differ on these inputs")
    steps = int(x.shape[0] * x.shape[1])
    per_step = (ran.ticks or 0) * cmd.INSTRUCTIONS_PER_TICK / max(1, steps)
    most = (ran.most_ticks or 0) * cmd.INSTRUCTIONS_PER_TICK
    usage.timing = realtime_record(per_step, most, PARTS[usage.part_key], net.dt, net.steps)
    usage.notes.append("the QEMU run's outputs equal the emulator's on these inputs, bit for bit")
    return usage


__all__ = ["CUsage", "usage_of_artefact", "estimate_artefact", "measured_code"]
