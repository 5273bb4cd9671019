"""The Xylo artefact directory: its format and files (``format.py``), written from a lowering (``write.py``),
read back and recognised (``read.py``)."""
