"""Evaluation backends behind one interface (:class:`Evaluator`): serial, a process pool, threads, Ray."""

from .backends import (BACKENDS, MAX_RETRIES, Evaluator, ProcessPoolEvaluator, SerialEvaluator, ThreadEvaluator,
                       check_worker_count, make_evaluator, worker_limit)

__all__ = ["BACKENDS", "Evaluator", "MAX_RETRIES", "ProcessPoolEvaluator", "SerialEvaluator", "ThreadEvaluator",
           "check_worker_count", "make_evaluator", "worker_limit"]
