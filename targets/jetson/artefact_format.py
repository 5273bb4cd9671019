"""The Jetson artefact's directory format, light to import (``identify`` asks every target about every path):
its manifest's format tag, the files it lists, the TensorRT engines tolerated beside them
(``kit.manifest.ManifestFormat``). What the manifest holds is ``manifest.py``'s."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from snncc.targets.kit.manifest import ManifestFormat

FORMAT = "snncc-jetson-artefact"
FORMAT_VERSION = 1


MANIFEST = "manifest.json"
EXECUTABLE = ("build_engine.sh", "run.py")
WRITTEN_FILES = (MANIFEST, *EXECUTABLE)


def listed_files(manifest: Mapping[str, Any]) -> dict[str, str | None]:
    """The artefact's own files as its manifest names them (the manifest, the recipe and runner, every
    variant's model file); the Jetson manifest records no file hashes (the summary does)."""
    names = set(WRITTEN_FILES)
    for variant in manifest.get("variants") or []:
        if isinstance(variant, dict) and isinstance(variant.get("file"), str):
            names.add(variant["file"])
    return {name: None for name in sorted(names)}


def engines(manifest: Mapping[str, Any]) -> set[str]:
    """The TensorRT ``.plan`` engines ``build_engine.sh`` writes beside the variants (the board's, not ours)."""
    return {name.replace(".onnx", ".plan") for name in listed_files(manifest) if name.endswith(".onnx")}


def _where(manifest: Mapping[str, Any], name: str) -> str:
    """The manifest entry that names the file ``name``."""
    for i, variant in enumerate(manifest.get("variants") or []):
        if isinstance(variant, dict) and variant.get("file") == name:
            return f"{MANIFEST}/variants/{i}/file"
    return MANIFEST


def _describe(manifest: Mapping[str, Any]) -> str:
    return f"Jetson artefact (ONNX opset {manifest.get('opset')}, JetPack {manifest.get('jetpack')})"


JETSON_FORMAT = ManifestFormat(format=FORMAT, target="jetson", kind="an snncc Jetson artefact",
                               files=listed_files, own_extra=engines, describe=_describe, executable=EXECUTABLE,
                               model_key="loaded_model", where=_where)
