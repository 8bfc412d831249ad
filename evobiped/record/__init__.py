"""Recording and figures: the only code that imports rerun and matplotlib.

Both are imported lazily inside the modules that need them
(:mod:`.rerun_recorder`, :mod:`.evolution_log`, :mod:`.figures`), so
``import evobiped`` and ``import evobiped.record`` stay light.

* :mod:`.trajectory` - an episode listener that collects one individual's episode;
* :mod:`.geometry` - every geom of any MuJoCo model as drawable shapes;
* :mod:`.rerun_recorder` - a trajectory as a Rerun recording with a blueprint;
* :mod:`.evolution_log` - best/mean/worst fitness per generation to Rerun;
* :mod:`.figures` - the papers' figures as PNG;
* :mod:`.video` - frames of a replay without a display (MuJoCo's offscreen renderer) as MP4/GIF and into Rerun;
* :mod:`.viewer` - streaming to a running viewer (address check, bounded flush);
* :mod:`.source` - what ``evobiped replay SOURCE`` reads (run directory or genome file);
* :mod:`.replay` - re-simulate, record, compare fitness.
"""
