"""The three papers' experiments and analyses, apart from the framework core.

* :mod:`evobiped.experiments.reil`: Reil & Husbands 2002 - many-run studies
  (success rates, Fig. 5's distance histograms) and their statistics.
* :mod:`evobiped.experiments.taga`: Taga, Yamaguchi & Shimizu 1991 - the Taga
  walker under u0 sweeps, pushes, slopes and ground changes; stride metrics;
  the paper's figures.
* :mod:`evobiped.experiments.g3`: Pribe, Grossberg & Cohen 1997 - the G3
  network under GO schedules, gait analysis, the paper's figures.

Experiments import the core (bodies, controllers, tasks, episode, evolution,
record); the core never imports an experiment.  Only the CLI and the scripts
reach both.
"""
