"""Recording and figures: the only code that imports rerun and matplotlib, or renders frames.

Both are imported lazily inside the modules that need them, so ``import evobiped`` and
``import evobiped.record`` stay light.  By kind:

* :mod:`.trajectory` - an episode listener that collects one individual's episode;
* :mod:`.geometry` - every geom of any MuJoCo model as drawable shapes;
* :mod:`.source` - what ``evobiped replay SOURCE`` reads (run directory or genome file);
* :mod:`.video` - frames of a replay without a display (MuJoCo's offscreen renderer) as MP4/GIF and into Rerun;
* :mod:`.recordings` - Rerun recordings: an episode's (:mod:`.recordings.rerun_recorder`), a replay's
  (:mod:`.recordings.replay_recording`), a run's fitness per generation (:mod:`.recordings.evolution_log`), and
  streaming to a running viewer (:mod:`.recordings.viewer`);
* :mod:`.png` - PNG figures: the papers' (:mod:`.png.figures`), steering, footfalls, robustness, commands, a
  MAP-Elites archive, a comparison.
"""
