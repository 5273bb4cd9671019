"""Jetson target (ONNX, TensorRT recipe, runner): built in its own issue."""

from snncc.errors import SnnccError


class _Pending:
    name = "jetson"
    description = "NVIDIA Jetson (not built yet)"
    output_kind = "directory"

    def lower(self, graph, options):
        raise SnnccError("the Jetson target is not built in this version of snncc yet", field="--target jetson")


target = _Pending()
