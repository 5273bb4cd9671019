"""What ``snncc map`` and ``snncc report`` read: a Loihi bundle, or a model file lowered for Loihi first."""

from __future__ import annotations

from pathlib import Path

from snncc.errors import SnnccError

MODEL_SUFFIXES = (".pt", ".pth", ".ckpt", ".snnir", ".nir")


def load_network(source: Path, timing: str | None = None, scale: str | None = None, replicas: int | None = None):
    """A LoihiNetwork from a bundle, or from a model file lowered with the Loihi target
    (``timing``/``scale``/``replicas`` apply only to lowering a model file: given with a bundle, they are refused)."""
    import h5py

    source = Path(source)
    if not source.is_file():
        from snncc.artefact_paths import LOIHI_BUNDLE, wrong_path

        raise wrong_path(source, f"{LOIHI_BUNDLE} or a model file")
    if h5py.is_hdf5(str(source)) and source.suffix.lower() != ".nir":   # a NIR graph is HDF5 too
        from snncc.targets.loihi.bundle.hdf5 import read_bundle

        for flag, value in (("--timing", timing), ("--scale", scale), ("--replicas", replicas)):
            if value is not None:
                raise SnnccError("does not apply to a Loihi bundle (its timing, weight scale and replicas are fixed); "
                                 "it applies only when map lowers a model file", file=str(source), field=flag)
        return read_bundle(source)
    if source.suffix.lower() not in MODEL_SUFFIXES:
        raise SnnccError(f"expected a Loihi bundle (HDF5) or a model file ({', '.join(MODEL_SUFFIXES)})",
                         file=str(source), field="format")
    from snncc.frontends import load_model
    from snncc.targets.loihi.lowering.lower import lower_artefact

    graph = load_model(source)
    return lower_artefact(graph, {"timing": timing, "scale": scale, "replicas": replicas,
                                  "source": str(source)}).network
