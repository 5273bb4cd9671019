"""``snncc check`` of a Xylo artefact: the written artefact against the float graph, stage by stage
(``stages.py``)."""
