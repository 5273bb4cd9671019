"""NeuroBench 2.3's metrics of a deployed artefact (the one implementation is ``snncc.measure.neurobench``).

A target lists its synapses as stored (``Projection(source, target, weight, delay)``: a weight rounded to 0 is
zero), runs its own emulator on the inputs and feeds each chunk's spikes, by population, to a ``Tally``; the
footprint is what the artefact holds on the device, with what was counted stated.
"""

from __future__ import annotations

from snncc.measure.neurobench import (
    NeuroBenchFigures, Projection, Tally, activation_sparsity, connection_sparsity, figures, from_tally,
    graph_projections, is_pooling, synaptic_operations,
)

__all__ = ["NeuroBenchFigures", "Projection", "Tally", "activation_sparsity", "connection_sparsity", "figures",
           "from_tally", "graph_projections", "is_pooling", "synaptic_operations"]
