"""Rerun recordings: an episode's with a blueprint, a replay's, a run's fitness per generation, and a live viewer."""
