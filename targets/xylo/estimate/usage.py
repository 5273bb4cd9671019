"""``snncc map`` / ``snncc report`` of a Xylo spec: what it uses against each chip's limits, and whether
it runs in real time.

Usage per chip (``chip.CHIPS``): input channels, hidden and output neurons, input and output expansion
neurons, synaptic currents per hidden neuron, the largest recurrent fan-out, alias targets; each
``used / limit`` and whether it fits. Synapses: the non-zero weights of each matrix. Real time
(``real_time.py``): core clock cycles per step, worst case (every channel and neuron active) and at
event rates (measured on the given inputs in snncc's emulator, or the lowering's calibration rates),
against ``dt`` at the Audio 2 HDK's fastest core clock: an ESTIMATE from per-operation cycle costs,
not a measurement. No energy or power figure: none for this network was published, and snncc states
none it did not measure.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from snncc.targets.xylo.chip import CHIPS, XyloChip
from snncc.targets.xylo.estimate.real_time import verdict

NO_ENERGY = ("no energy or power figure: snncc gives one only from a published measurement of the network, and none "
             "exists for this one (Xylo's energy per event was not measured here: no board)")


def _input_expansion(spec) -> int:
    """Hidden neurons 0 .. k - 1 the inputs must reach: k = 1 + the last one with a non-zero input weight."""
    w = spec.weights_in if spec.weights_in.ndim == 3 else spec.weights_in[:, :, None]
    nz = np.flatnonzero(np.any(w != 0, axis=(0, 2)))
    return int(nz[-1] + 1) if nz.size else 0


def _output_expansion(spec) -> int:
    """The last k hidden neurons the outputs must read: from the first row of weights_out with a non-zero weight."""
    nz = np.flatnonzero(np.any(spec.weights_out != 0, axis=1))
    return int(spec.n_oen - nz[0]) if nz.size else 0


def chip_usage(spec, chip: XyloChip) -> dict[str, dict[str, Any]]:
    """Field -> {used, limit, fits} for ``spec`` on ``chip``."""
    syn = max(w.shape[2] if w.ndim == 3 and np.any(w[:, :, 1:]) else 1 for w in (spec.weights_in, spec.weights_rec))
    fan = spec.fanout()
    used = {
        "input channels": (spec.n_in, chip.max_inputs),
        "hidden neurons": (spec.n_hidden, chip.max_hidden),
        "output neurons": (spec.n_out, chip.max_outputs),
        "input expansion neurons": (_input_expansion(spec), chip.max_input_expansion),
        "output expansion neurons": (_output_expansion(spec), chip.max_output_expansion),
        "synaptic currents per hidden neuron": (syn, chip.synapses_per_hidden),
        "recurrent fan-out (largest)": (int(fan.max()) if fan.size else 0, chip.max_fanout),
        "alias targets per neuron (largest)": (max((len(a) for a in spec.aliases), default=0), chip.max_alias_targets),
    }
    return {k: {"used": int(u), "limit": int(lim), "fits": int(u) <= int(lim)} for k, (u, lim) in used.items()}


def synapses(spec) -> dict[str, int]:
    return {name: int(np.count_nonzero(getattr(spec, name))) for name in ("weights_in", "weights_rec", "weights_out")}


def event_rates(spec, x: np.ndarray, input_pad: int = 0, output_lag: int = 0) -> dict[str, float]:
    """Share of (sample, step, channel / neuron) entries with at least one event, on inputs ``x`` run in the emulator."""
    from snncc.targets.xylo.emulation.emulator import emulate

    b, t, c = x.shape
    run = np.zeros((b, t + max(input_pad, output_lag), c), np.uint8)
    run[:, input_pad:input_pad + t] = np.minimum(x, 255)
    res = emulate(spec, run, record=True)
    return {"input": float(np.mean(x > 0)), "hidden": float(np.mean(res.spikes > 0)),
            "output": float(np.mean(res.output_spikes > 0))}


@dataclass
class XyloUsage:
    """What a Xylo network uses on every chip, and its real-time ESTIMATE (``map`` and ``report``)."""

    source: str
    chip: str                                   # the chip it was compiled for
    dt: float
    usage: dict[str, dict[str, dict[str, Any]]]  # chip key -> field -> used/limit/fits
    synapses: dict[str, int]
    real_time: dict[str, Any]
    rates_from: str
    energy: str = NO_ENERGY
    notes: list[str] = field(default_factory=list)

    def fits(self, chip: str) -> bool:
        return all(v["fits"] for v in self.usage[chip].values())

    def to_dict(self) -> dict[str, Any]:
        return {"target": "xylo", "source": self.source, "chip": self.chip, "dt": self.dt,
                "fits": {k: self.fits(k) for k in self.usage}, "usage": self.usage, "synapses": self.synapses,
                "real_time": self.real_time, "rates_from": self.rates_from, "energy": self.energy,
                "notes": list(self.notes)}

    def as_dict(self) -> dict[str, Any]:
        return self.to_dict()

    def render_text(self, console) -> None:
        from rich.table import Table

        table = Table(title=f"Xylo usage of {self.source} (compiled for {CHIPS[self.chip].name})")
        table.add_column("")
        for key in self.usage:
            table.add_column(f"{CHIPS[key].name} ({key})")
        for name in next(iter(self.usage.values())):
            cells = []
            for key in self.usage:
                u = self.usage[key][name]
                cells.append(f"{u['used']} / {u['limit']}" + ("" if u["fits"] else "  EXCEEDS"))
            table.add_row(name, *cells)
        table.add_row("fits", *["yes" if self.fits(k) else "NO" for k in self.usage])
        console.print(table)
        console.print(f"synapses (non-zero weights): {self.synapses}", markup=False)
        console.print(f"real time {verdict(self.real_time, self.rates_from)}", markup=False, soft_wrap=True)
        console.print(self.energy, markup=False, soft_wrap=True)
        for note in self.notes:
            console.print(f"note: {note}", markup=False, soft_wrap=True)

    def plot(self, path: str | Path) -> None:
        """Each chip's usage in % of its limits as a PNG, written atomically: one horizontal bar per limit and chip
        (the limits' names readable on the left), the artefact and the chip it was compiled for in the title."""
        import matplotlib.pyplot as plt

        from snncc.targets.kit.writing import atomic_path

        fig = self.figure()
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png")
        plt.close(fig)

    def figure(self):   # noqa: ANN201 (a matplotlib Figure)
        """The usage plot (``plot``) as a matplotlib figure."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        names = list(next(iter(self.usage.values())))
        chips = list(self.usage)
        height = 0.8 / len(chips)
        fig, ax = plt.subplots(figsize=(9.0, 1.0 + 0.55 * len(names)), dpi=100)
        rows = np.arange(len(names))
        for j, key in enumerate(chips):
            pct = [100.0 * self.usage[key][n]["used"] / max(1, self.usage[key][n]["limit"]) for n in names]
            ax.barh(rows + (j - (len(chips) - 1) / 2) * height, pct, height,
                    label=f"{CHIPS[key].name} ({key})" + (" - compiled for" if key == self.chip else ""))
        ax.axvline(100.0, color="k", lw=1, ls="--")
        ax.set_yticks(rows)
        ax.set_yticklabels(names, fontsize=9)
        ax.invert_yaxis()
        ax.set_xlabel("% of the chip's limit (dashed: the limit)")
        ax.set_title(f"Xylo usage of {Path(self.source).name} (compiled for {CHIPS[self.chip].name}, {self.chip})",
                     fontsize=10)
        ax.legend(fontsize=8, loc="lower right")
        fig.tight_layout()
        return fig


def usage_of(spec, *, source: str, chip: str, rates: dict[str, float], rates_from: str) -> XyloUsage:
    from snncc.targets.xylo.estimate.real_time import real_time

    return XyloUsage(source, chip, float(spec.dt), {k: chip_usage(spec, c) for k, c in CHIPS.items()}, synapses(spec),
                     real_time(spec, float(spec.dt), rates).as_dict(), rates_from)


def usage_of_artefact(path: Path) -> XyloUsage:
    """The usage of a written artefact, event rates from the calibration its lowering recorded."""
    from snncc.targets.xylo.artefact.read import read_artefact

    written = read_artefact(path)
    rates = dict(written.manifest.get("real_time", {}).get("rates") or {})
    return usage_of(written.spec, source=str(path), chip=written.chip, rates=rates,
                    rates_from="the lowering's calibration inputs (manifest.json)")


def usage_on_inputs(path: Path, x: np.ndarray, note: str = "") -> XyloUsage:
    """``report``: the usage with event rates measured on ``x`` (B, T, C) in snncc's emulator."""
    from snncc.targets.xylo.emulation.run_artefact import artefact_inputs
    from snncc.targets.xylo.artefact.read import read_artefact

    written = read_artefact(path).runnable()
    x = artefact_inputs(x, written.spec.n_in, None)
    rates = event_rates(written.spec, x, written.input_pad, written.output_lag)
    return usage_of(written.spec, source=str(path), chip=written.chip, rates=rates,
                    rates_from=f"{x.shape[0]} sample(s) of {x.shape[1]} steps" + (f" ({note})" if note else ""))
