"""PNG figures (matplotlib): the papers' figures, steering, footfalls, robustness, commands, archives, comparisons."""
