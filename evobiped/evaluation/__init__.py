"""Evaluation backends behind one interface (:class:`Evaluator`): serial, a process pool, threads, Ray; made by name
(:func:`make_evaluator`), with one retry loop for the local workers (:class:`~.base.RetryingEvaluator`) and their
testing hook passed in (:mod:`.faults`)."""

from .backends import BACKENDS, make_evaluator
from .base import MAX_RETRIES, Evaluator, RetryingEvaluator
from .limits import check_worker_count, worker_limit
from .processes import ProcessPoolEvaluator
from .serial import SerialEvaluator
from .threads import ThreadEvaluator

__all__ = ["BACKENDS", "Evaluator", "MAX_RETRIES", "ProcessPoolEvaluator", "RetryingEvaluator", "SerialEvaluator",
           "ThreadEvaluator", "check_worker_count", "make_evaluator", "worker_limit"]
