"""The core map: which neurons sit on which core, and what each core uses of every limit.

Typed records: ``CoreMap`` holds one ``CoreRecord`` per core, each with the ``LayerSlice``s placed
on it and a ``CoreUsage`` (one integer per per-core limit of ``ChipSpec.limits()``). One record,
three renderings: ``to_dict()`` (JSON, stored in the bundle), ``render_text(console)``
and ``plot(path)`` (utilisation per core as a PNG). Core ids are global; chip = core // cores
per chip; tile = (core % cores per chip) // cores per tile (cores placed in id order).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from snncc.targets.loihi.mapping.resources import LIMIT_TITLES, LOIHI1, ChipSpec

USAGE_FIELDS = ("neurons", "input_axons", "output_axons", "synapse_bits", "vth_profiles",
                "compartment_profiles", "voltage_limits")
SHOWN = ("neurons", "input_axons", "output_axons", "synapse_bits")


@dataclass
class LayerSlice:
    """Neurons ``start..stop-1`` of one layer, placed on a core."""

    layer: str
    index: int          # layer index in the mapped network (0 = input)
    start: int
    stop: int           # neurons start..stop-1 of the layer

    @property
    def size(self) -> int:
        return self.stop - self.start


@dataclass(frozen=True)
class CoreUsage:
    """What one core uses of each per-core limit (resources.py: ``ChipSpec.limits()`` has the same names)."""

    neurons: int
    input_axons: int
    output_axons: int
    synapse_bits: int
    vth_profiles: int
    compartment_profiles: int
    voltage_limits: int

    def as_dict(self) -> dict[str, int]:
        return {k: int(getattr(self, k)) for k in USAGE_FIELDS}

    @classmethod
    def from_mapping(cls, row) -> "CoreUsage":
        """From any mapping holding the seven fields (a JSON core row, or per-core values)."""
        return cls(**{k: int(row[k]) for k in USAGE_FIELDS})


@dataclass
class CoreRecord:
    """One core: its global id, its chip (id // cores per chip), the slices on it and its usage."""

    core: int
    chip: int
    layers: list[LayerSlice]
    usage: CoreUsage


@dataclass
class CoreMap:
    """The map of a network on a chip: per-core records, the lower bound, and how it was found."""

    chip: ChipSpec
    cores: list[CoreRecord]
    lower_bound: int
    lower_bound_method: str
    method: str
    layer_limits: dict[str, str] = field(default_factory=dict)   # layer -> what set its core count
    transforms: list[dict] = field(default_factory=list)         # fan-in relays inserted (fanin.py)
    network_layers: list[dict] = field(default_factory=list)     # name, kind, n of the mapped network
    network: Any = None                                          # the mapped LoihiNetwork (not serialised)

    # -- derived -------------------------------------------------------------------------------
    @property
    def n_cores(self) -> int:
        return len(self.cores)

    @property
    def n_chips(self) -> int:
        return 1 + max((c.chip for c in self.cores), default=0) if self.cores else 0

    @property
    def optimal(self) -> bool:
        return self.n_cores == self.lower_bound

    def percent(self, core: CoreRecord) -> dict[str, float]:
        limits = self.chip.limits()
        return {k: round(100.0 * getattr(core.usage, k) / limits[k], 2) for k in USAGE_FIELDS}

    def totals(self) -> dict[str, int]:
        return {k: int(sum(getattr(c.usage, k) for c in self.cores)) for k in SHOWN}

    def peak_percent(self) -> dict[str, float]:
        return {k: max((self.percent(c)[k] for c in self.cores), default=0.0) for k in USAGE_FIELDS}

    @property
    def binding_constraint(self) -> str:
        """The resource closest to its limit on the fullest core (what stops a denser packing)."""
        peak = self.peak_percent()
        keys = USAGE_FIELDS[:-1]          # a single allowed vmin/vmax setting is always "100 %" used
        return max(keys, key=lambda k: (peak[k], -keys.index(k)))

    def tile_of(self, core: int) -> int:
        return (core % self.chip.cores_per_chip) // self.chip.cores_per_tile

    def core_of_neuron(self) -> dict[int, "Any"]:
        """Layer index -> int array (n,) of the core each neuron sits on."""
        import numpy as np

        sizes = {d["index"]: d["n"] for d in self.network_layers}
        out = {i: np.full(n, -1, np.int64) for i, n in sizes.items() if i > 0}
        for c in self.cores:
            for s in c.layers:
                out[s.index][s.start:s.stop] = c.core
        return out

    # -- JSON ------------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        limits = self.chip.limits()
        cores = []
        for c in self.cores:
            row = {"core": c.core, "chip": c.chip, "core_in_chip": c.core % self.chip.cores_per_chip,
                   "tile": self.tile_of(c.core)}
            row.update(c.usage.as_dict())
            row["layers"] = [{"layer": s.layer, "index": s.index, "start": s.start, "stop": s.stop}
                             for s in c.layers]
            row["percent"] = self.percent(c)
            cores.append(row)
        return {
            "chip": self.chip.name,
            "limits": limits,
            "cores": cores,
            "n_cores": self.n_cores,
            "n_chips": self.n_chips,
            "lower_bound": self.lower_bound,
            "lower_bound_method": self.lower_bound_method,
            "optimal": self.optimal,
            "binding_constraint": self.binding_constraint,
            "peak_percent": self.peak_percent(),
            "totals": self.totals(),
            "method": self.method,
            "layer_limits": dict(self.layer_limits),
            "transforms": list(self.transforms),
            "network_layers": list(self.network_layers),
            "chip_spec": self.chip.to_dict(),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "CoreMap":
        chip = ChipSpec.from_dict(d["chip_spec"]) if "chip_spec" in d else LOIHI1
        cores = [CoreRecord(core=int(c["core"]), chip=int(c["chip"]),
                            layers=[LayerSlice(s["layer"], int(s["index"]), int(s["start"]), int(s["stop"]))
                                    for s in c["layers"]],
                            usage=CoreUsage.from_mapping(c))
                 for c in d["cores"]]
        return cls(chip=chip, cores=cores, lower_bound=int(d["lower_bound"]),
                   lower_bound_method=d.get("lower_bound_method", ""), method=d.get("method", ""),
                   layer_limits=dict(d.get("layer_limits", {})), transforms=list(d.get("transforms", [])),
                   network_layers=list(d.get("network_layers", [])))

    # -- text --------------------------------------------------------------------------------------
    def render_text(self, console, max_rows: int = 64) -> None:
        from rich.table import Table

        table = Table(title=f"Core map on {self.chip.name} ({self.n_cores} cores, {self.n_chips} chip(s))")
        for col in ("core", "chip", "layers [neurons]", "neurons", "input axons", "output axons", "synapse bits"):
            if col.startswith("layers"):
                table.add_column(col, overflow="fold", min_width=16)
            else:
                table.add_column(col, justify="right")
        shown = self.cores if len(self.cores) <= max_rows else self.cores[: max_rows - 1]
        for c in shown:
            pct = self.percent(c)
            table.add_row(
                str(c.core), str(c.chip),
                ", ".join(f"{s.layer}[{s.start}:{s.stop}]" for s in c.layers),
                *(f"{getattr(c.usage, k):,} ({pct[k]:.1f}%)" for k in SHOWN))
        if len(shown) < len(self.cores):
            table.add_row("...", "", f"{len(self.cores) - len(shown):,} more cores (use --json)", "", "", "", "")
        console.print(table)
        limits = self.chip.limits()
        tot = self.totals()
        console.print("totals: " + ", ".join(f"{LIMIT_TITLES[k].split(' per ')[0]} {tot[k]:,}" for k in SHOWN))
        console.print("limits per core: " + ", ".join(f"{k} {v:,}" for k, v in limits.items()))
        verdict = "optimal (equals the lower bound)" if self.optimal else f"{self.n_cores - self.lower_bound} above the lower bound"
        console.print(f"cores: {self.n_cores} on {self.n_chips} chip(s); lower bound {self.lower_bound} "
                      f"({self.lower_bound_method}); {verdict}")
        console.print(f"binding constraint: {LIMIT_TITLES[self.binding_constraint]} "
                      f"(peak {self.peak_percent()[self.binding_constraint]:.1f}%)")
        if self.layer_limits:
            console.print("per layer: " + "; ".join(f"{k}: {v}" for k, v in self.layer_limits.items()))
        console.print(f"method: {self.method}")
        for t in self.transforms:
            console.print(f"fan-in relays for layer '{t['layer']}': {t['copied_exactly']} of {t['fan_in']} "
                          f"sources copied exactly, {t['through_rate_relays']} through rate relays; "
                          f"timing: {t['timing']}; accuracy: {t['accuracy']}")

    # -- picture -----------------------------------------------------------------------------------
    def drawn_limits(self) -> tuple[str, ...]:
        """The per-core limits the picture draws: the four shown in the table, and the binding one where it is
        another (a profile count): a title never names a limit the picture does not draw."""
        return SHOWN + ((self.binding_constraint,) if self.binding_constraint not in SHOWN else ())

    def figure(self):
        """The picture as a matplotlib figure (``plot`` writes it): above, utilisation (% of each drawn limit) per
        core; below, which population sits on which core (neurons of each layer per core, stacked)."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import numpy as np

        drawn = self.drawn_limits()
        pct = np.array([[self.percent(c)[k] for k in drawn] for c in self.cores]).reshape(-1, len(drawn))
        ids = np.arange(len(self.cores))
        fig, (ax, low) = plt.subplots(2, 1, figsize=(max(6.0, min(18.0, 0.35 * len(ids) + 3)), 6.5), dpi=100,
                                      sharex=True, gridspec_kw={"height_ratios": [3, 2]})
        if len(ids) <= 64:
            width = 0.8 / len(drawn)
            for j, k in enumerate(drawn):
                ax.bar(ids + (j - (len(drawn) - 1) / 2) * width, pct[:, j], width, label=k.replace("_", " "))
            ax.set_xticks(ids)
        else:
            for j, k in enumerate(drawn):
                ax.plot(ids, pct[:, j], drawstyle="steps-mid", lw=0.8, label=k.replace("_", " "))
        ax.axhline(100.0, color="k", lw=1, ls="--")
        for b in range(1, self.n_chips):
            for a in (ax, low):
                a.axvline(b * self.chip.cores_per_chip - 0.5, color="grey", lw=0.8, ls=":")
        ax.set_ylabel("% of per-core limit")
        ax.set_ylim(0, 125)
        ax.set_title(f"{self.chip.name}: {self.n_cores} cores on {self.n_chips} chip(s) "
                     f"(lower bound {self.lower_bound}; binding: {self.binding_constraint.replace('_', ' ')})",
                     fontsize=9)
        ax.legend(fontsize=8, loc="upper center", ncol=len(drawn), frameon=False)
        layers = list(dict.fromkeys(s.layer for c in self.cores for s in c.layers))
        per = np.zeros((len(layers), len(ids)))
        for j, c in enumerate(self.cores):
            for s_ in c.layers:
                per[layers.index(s_.layer), j] += s_.size
        bottom = np.zeros(len(ids))
        for k, name in enumerate(layers):
            low.bar(ids, per[k], 0.8, bottom=bottom, label=name)
            bottom += per[k]
        low.set_xlabel("core")
        low.set_ylabel("neurons per population")
        low.set_title("populations on each core", fontsize=9)
        low.legend(fontsize=8, loc="upper center", ncol=min(len(layers), 6), frameon=False)
        fig.tight_layout()
        return fig

    def plot(self, path: str | Path) -> None:
        """``figure()`` as a PNG, written atomically."""
        import matplotlib.pyplot as plt

        from snncc.targets.kit.writing import atomic_path

        fig = self.figure()
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png")
        plt.close(fig)
