"""``snncc map``: place a Loihi bundle (or a model, lowered first) on cores and report the core map."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from snncc.cli.app import app
from snncc.cli.output import console, print_json
from snncc.errors import SnnccError

MODEL_SUFFIXES = (".pt", ".pth", ".ckpt", ".snnir", ".nir")


def load_network(source: Path, timing: str | None = None, scale: str | None = None):
    """A LoihiNetwork from a bundle, or from a model file lowered with the Loihi target
    (``timing``/``scale`` apply only to lowering a model file: given with a bundle, they are refused)."""
    import h5py

    if not source.is_file():
        raise SnnccError("file does not exist", file=str(source))
    if h5py.is_hdf5(str(source)):
        from snncc.targets.loihi.bundle import read_bundle

        for flag, value in (("--timing", timing), ("--scale", scale)):
            if value is not None:
                raise SnnccError("does not apply to a Loihi bundle (its timing and weight scale are fixed); "
                                 "it applies only when map lowers a model file", file=str(source), field=flag)
        return read_bundle(source)
    if source.suffix.lower() not in MODEL_SUFFIXES:
        raise SnnccError(f"expected a Loihi bundle (HDF5) or a model file ({', '.join(MODEL_SUFFIXES)})",
                         file=str(source))
    from snncc.frontends import load_model
    from snncc.targets import get_target

    graph = load_model(source)
    given = {"timing": timing, "scale": scale}
    artefact = get_target("loihi").lower(graph, {**{k: v for k, v in given.items() if v is not None}, "source": str(source)})
    return artefact.network


@app.command("map")
def map_command(
    source: Path = typer.Argument(..., help="Loihi bundle (HDF5) or a model file (.pt/.pth/.ckpt/.snnir/.nir), lowered with the Loihi target first."),
    json_out: bool = typer.Option(False, "--json", help="Print the core map as JSON."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Also draw utilisation per core as a PNG (written atomically)."),
    timing: Optional[str] = typer.Option(None, "--timing", help="For a model file: Loihi timing 'exact' (default) or 'paper' (the authors' export)."),
    scale: Optional[str] = typer.Option(None, "--scale", help="For a model file: Loihi weight scale rule (auto (default) | global | per-layer | split)."),
) -> None:
    """Place every population on Loihi 1 cores under all per-core limits; print the core map."""
    from snncc.targets.loihi.partition import map_network

    network = load_network(source, timing, scale)
    try:
        cmap = map_network(network)
    except SnnccError as err:
        raise err.with_file(str(source))
    if plot is not None:
        cmap.plot(plot)
    if json_out:
        print_json({"source": str(source), **cmap.to_dict()})
        return
    cmap.render_text(console)
    if plot is not None:
        console.print(f"wrote {plot}")
