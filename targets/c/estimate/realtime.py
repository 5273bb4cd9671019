"""Time and energy per step of a C artefact on a part: instructions counted in QEMU, the rest an ESTIMATE.

    instructions   the Cortex-M4 build (``-mcpu=cortex-m4 -mthumb -Os``) run in QEMU (MPS2 AN386, ``-icount
                   shift=0``: one instruction per ns of virtual time) with SysTick read around every ``snn_step``
                   (25 MHz: 40 instructions a tick), on the given inputs: mean per step and the most in one step.
                   Counted, not modelled; resolution 40 instructions per step read.
    cycles         instructions x CPI, the cycles-per-instruction ASSUMED for the part's core (``options.CPI``:
                   1.5 for a Cortex-M4 running from flash through its prefetch accelerator, loads and taken
                   branches costing 2-3 cycles, most ALU and multiply instructions 1): an ESTIMATE
    time per step  cycles / the part's clock; real time when the mean step fits in dt (the worst step is shown
                   beside it); the margin is 1 - cycles / (clock x dt)
    energy         run current (the datasheet's uA/MHz x MHz) x supply voltage (3 V assumed) x time: per step
                   = uA/MHz x V x cycles pJ; per sample x steps. An ESTIMATE from a headline figure measured by the
                   vendor on other code; sleep between steps and peripherals not counted.

For a Cortex-M0+ part the instruction count is still the Cortex-M4 build's (QEMU's M0 board is not used): an
M0+ lacks 64-bit multiplies, so its own count is higher; the figure is then a lower bound and says so.
"""

from __future__ import annotations

from typing import Any

from snncc.targets.c.options import CPI


def realtime_record(instructions: float, most: int, part: dict[str, Any], dt: float, steps: int) -> dict[str, Any]:
    """Cycles, time, real-time verdict and energy (ESTIMATES) from measured instructions per step."""
    cpi = CPI[part["core"]]
    cycles = instructions * cpi
    worst = most * cpi
    budget = part["clock_hz"] * dt
    energy_step_j = part["run_ua_per_mhz"] * 3.0 * cycles * 1e-12
    record = {
        "instructions_per_step": float(instructions), "most_instructions_in_a_step": int(most),
        "cpi_assumed": cpi, "cycles_per_step": float(cycles), "worst_step_cycles": float(worst),
        "clock_hz": part["clock_hz"], "cycle_budget_per_step": float(budget),
        "time_per_step_s": cycles / part["clock_hz"], "dt_s": float(dt),
        "real_time": bool(cycles <= budget), "worst_step_real_time": bool(worst <= budget),
        "margin": 1.0 - cycles / budget if budget else None,
        "energy_per_step_j": energy_step_j, "energy_per_sample_j": energy_step_j * steps, "steps_per_sample": steps,
        "supply_volts": 3.0, "run_ua_per_mhz": part["run_ua_per_mhz"], "source": part["source"],
        "label": "ESTIMATE: instructions counted in QEMU (Cortex-M4 build); cycles = instructions x an assumed CPI; "
                 "energy = the datasheet's run current per MHz x 3 V x time",
    }
    if part["core"] != "Cortex-M4 (FPU)":
        record["note"] = (f"{part['core']}: the instruction count is the Cortex-M4 build's; this core has no 64-bit "
                          "multiply instruction, so its count is higher: a lower bound")
    return record


__all__ = ["realtime_record"]
