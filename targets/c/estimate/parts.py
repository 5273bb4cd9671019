"""The microcontrollers a C artefact is costed against: flash, RAM, clock and run-mode current, each part's
figures from its datasheet's first page (features list), cited by document number and revision.

Plain data, no imports: ``options.py`` takes the keys from here (``--mcu``), the estimate the figures.
The run-mode current is the datasheet's headline "µA/MHz in Run mode" (typical, at 25 °C, measured by the
vendor on Dhrystone-like code from flash): an energy figure derived from it is an ESTIMATE, not a
measurement of this network's code.
"""

from __future__ import annotations

PARTS: dict[str, dict] = {
    "stm32l431rc": {
        "name": "STMicroelectronics STM32L431RC",
        "core": "Cortex-M4 (FPU)",
        "clock_hz": 80_000_000,
        "flash_bytes": 256 * 1024,
        "ram_bytes": 64 * 1024,
        "run_ua_per_mhz": 84.0,
        "source": "STM32L431xx datasheet, DS11453 Rev 3 (May 2018), page 1 (features): up to 80 MHz, "
                  "up to 256 KB Flash, 64 KB SRAM, 84 uA/MHz run mode",
    },
    "stm32l412kb": {
        "name": "STMicroelectronics STM32L412KB",
        "core": "Cortex-M4 (FPU)",
        "clock_hz": 80_000_000,
        "flash_bytes": 128 * 1024,
        "ram_bytes": 40 * 1024,
        "run_ua_per_mhz": 79.0,
        "source": "STM32L412xx datasheet, DS12469 Rev 7 (September 2019), page 1 (features): up to 80 MHz, "
                  "up to 128 KB Flash, 40 KB SRAM, 79 uA/MHz run mode (LDO mode)",
    },
    "stm32l031k6": {
        "name": "STMicroelectronics STM32L031K6",
        "core": "Cortex-M0+",
        "clock_hz": 32_000_000,
        "flash_bytes": 32 * 1024,
        "ram_bytes": 8 * 1024,
        "run_ua_per_mhz": 76.0,
        "source": "STM32L031x4/x6 datasheet, DS10668 Rev 6 (March 2018), page 1 (features): up to 32 MHz, "
                  "up to 32 KB Flash, 8 KB RAM, down to 76 uA/MHz in Run mode",
    },
}
PART_KEYS = tuple(PARTS)
DEFAULT_PART = "stm32l431rc"
SUPPLY_VOLTS = 3.0        # the supply an energy ESTIMATE assumes (the datasheets' typical-figure condition, V_DD = 3 V)

__all__ = ["PARTS", "PART_KEYS", "DEFAULT_PART", "SUPPLY_VOLTS"]
