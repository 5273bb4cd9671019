"""Target-neutral measurement: how a target's decisions agree with the float model's, with their
uncertainty (``agreement.py``), and how a written artefact is found, hashed and tied to its model
(``snncc.artefacts``)."""
