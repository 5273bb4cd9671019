"""What a Xylo network uses and costs: usage against every chip's limits (``usage.py``), the real-time ESTIMATE
(``real_time.py``), a search trial's figures (``search_figures.py``)."""
