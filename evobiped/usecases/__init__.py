"""What a user does with evobiped, each as one function the commands (``evobiped.cli``) and the experiments call:

- :mod:`.evolving`: validate a run's settings and directory, create or resume the run, then start the evaluator
  and evolve (``evobiped evolve``);
- :mod:`.replaying`: re-simulate a stored genome into a recording, figures and a video, and check its stored
  outcome (``evobiped replay``);
- :mod:`.selecting`: choose a run's walker by simulating its best candidates for longer (``evobiped select``).

A use case checks everything it is given before it writes a file or starts a worker; a command only turns flags
into its arguments and its result into lines.
"""
