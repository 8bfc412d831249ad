"""The commands about one walker: ``episode`` (one episode of it), ``robustness`` (the battery), ``bench`` (how fast
its episodes are evaluated), ``gait-report`` (its gait and the walking criteria), ``distill`` (a network taught by
it)."""
