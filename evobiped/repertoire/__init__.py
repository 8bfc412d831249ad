"""A gait repertoire: a MAP-Elites run's archive (:mod:`evobiped.optimizers.map_elites`) used as a set of gaits.

``elites``: the archive with the episode its genomes walk, which elites walk, one elite as a genome to replay,
the elite nearest a commanded speed and turning rate; ``speed``: a speed schedule that switches elites on the
fly; ``damage``: a damaged body (a weakened or locked joint, a shortened leg); ``trial_error``: Cully et al.
2015's intelligent trial and error that finds a gait of the archive that walks on it.
"""
