"""Deployment fine-tuning for Loihi 1 (capability ``finetune``, ``docs/finetune.md``): the lowered registers
trained through the chip's integer arithmetic towards the float graph as trained. Imports torch (on use).

    run.py             finetune_loihi: lower, search the starting points, train, export, check
    starts.py          the starting points searched before training (decay order, exponents, rescaled rounding)
    rescale.py         per-neuron scales and weights rounded with error feedback (a starting point)
    differentiable.py  the student: the emulator's rules as differentiable float64 tensors
    layer_bptt.py      one layer's time loop as one autograd function (hand-written backpropagation)
    export.py          the fine-tuned network read back as a float graph, and checked as compile checks
    artefact.py        the capability: a fine-tuned bundle (the kit's ``FinetunedArtefact``)
"""
