"""What every part of evobiped stands on, with no MuJoCo or biped in it: one-line errors, number checks, options and
schedules, atomic file writes, progress lines, provenance, the rendering backend."""
