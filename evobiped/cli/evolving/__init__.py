"""The commands about evolving and what a run holds: ``evolve``, ``compare`` (runs side by side), ``presets`` (the
named settings), ``replay``, ``select`` (a walker chosen among a run's), ``genome`` (a genome file made from a
walker's)."""
