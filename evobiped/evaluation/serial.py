"""The serial backend: every genome in one batch in this process."""

from __future__ import annotations

from ..episode import EpisodeConfig
from .base import Evaluator, evaluate_batch


class SerialEvaluator(Evaluator):
    """All genomes in one batch in this process."""

    def __init__(self, episode: EpisodeConfig):
        super().__init__(episode)
        self.episode = episode.build()

    def evaluate(self, genomes, key=None, context=None):
        return evaluate_batch(self.episode, genomes, key, context)
