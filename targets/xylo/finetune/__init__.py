"""Deployment fine-tuning on Xylo Audio 2: the v2 core's arithmetic in torch (``arithmetic.py``), the lowered
network in the model's time (``student.py``), the run and its artefact (``tuning.py``). Imports torch: import it
where training runs."""
