"""snncc's bit-exact emulator of the Xylo v2 core (``emulator.emulate``; the literal statement ``literal.py``, the
compiled kernel ``kernel.py``) and ``snncc emulate`` of a written artefact (``run_artefact.py``)."""
