"""snncc: a deployment compiler for spiking neural networks.

One IR with an explicit time model, one reference simulator that defines what a model means,
and targets (Loihi, Jetson) whose artefacts are checked against it.
"""

__version__ = "0.1.0"
