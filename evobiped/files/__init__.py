"""The files a user keeps: genome files, the run directory's format, a study's outcome, the presets."""
