"""The commands about a MAP-Elites run's archive used as gaits: ``repertoire`` (its summary and figures), ``adapt``
(intelligent trial and error on a damaged body), ``gait`` (a commanded walker followed through a schedule)."""
