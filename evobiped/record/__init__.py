"""Recording and figures: the only package code that imports rerun and matplotlib."""
