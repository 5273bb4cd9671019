"""Loihi 1 target (quantization, netx bundle, bit-exact emulator): built in its own issue."""

from snncc.errors import SnnccError


class _Pending:
    name = "loihi"
    description = "Intel Loihi 1 (not built yet)"
    output_kind = "file"

    def lower(self, graph, options):
        raise SnnccError("the Loihi target is not built in this version of snncc yet", field="--target loihi")


target = _Pending()
