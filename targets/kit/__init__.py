"""The target kit: what every target needs, written once (``docs/targets.md``, "The kit").

A target imports from snncc only ``snncc.targets.base`` (the interface), this kit and the IR it is
handed (``snncc.ir``); ``tests/targets/test_kit_boundary.py`` holds every built-in target to that,
and an out-of-tree test target proves a third party needs nothing else. Each module has one job:

    kit.artefact    an artefact's identity (``ArtefactIdentity``) and SHA-256, its files regular and inside it
    kit.writing     atomic writes of files and directories; byte-identical .npz bytes
    kit.manifest    a manifest directory: write, read (format tag, hashed files), identify, source identity
    kit.measured    "the artefact to measure": the one given, or compile's, written to a temporary directory
    kit.agreement   the one agreement rule (``snncc.measure.agreement``): Wilson interval, ties and silence
    kit.checks      the check record every target returns (``CheckReport``): stages, loss by cause, ceiling
    kit.reference   the float graph run by the IR reference: output counts in bounded chunks, one thread
    kit.finetuned   a fine-tuned artefact (``FinetunedArtefact``): written, summarised, its record
    kit.finetuning  the fine-tuning engine, teacher, input split and straight-through operations (torch)
    kit.profile     what an artefact costs (``Profile``: resources, real time, energy ESTIMATE, NeuroBench)
    kit.neurobench  NeuroBench 2.3's metrics from a deployed network's synapses and its emulator's spikes
    kit.search      a search trial's figures (``SearchCosts``: objectives, columns, front, published)
    kit.compute     one compute thread, rounding with error feedback, Ctrl-C around numba, memory bounds
    kit.inputs      arrays a user feeds an artefact: checked, laid out, seeded random spikes
    kit.emulation   what an emulation derives from its output spikes (samples, steps, counts, prediction)
    kit.timebase    the one time base: how many steps a sample lasts on every target
    kit.graphs      pure Graph -> Graph passes (linear folding, current biases, reset change)
    kit.models      model records other than a graph (a buffered classifier)
    kit.hdf5        an HDF5 artefact holds its own data: no link or external storage is read through
    kit.native      a C source compiled once by the system's compiler into a cached library (ctypes)

This module itself imports nothing heavy: the error types, the progress conventions and snncc's version.
"""

from __future__ import annotations

from snncc import __version__ as SNNCC_VERSION
from snncc.errors import InternalError, SnnccError, one_line
from snncc.progress import Progress, StepProgress, counting

__all__ = ["SnnccError", "InternalError", "one_line", "Progress", "StepProgress", "counting", "SNNCC_VERSION"]
