"""Straight-line walking: fitness = planar distance from the start (Reil & Husbands eq. 4).

    W = sqrt((x_t - x_0)^2 + (y_t - y_0)^2)

with t the time the evaluation ends (the 50 s limit, or the fall that ends it
early).  The walker's position is the pelvis centre projected on the ground;
for a simulation that blew up the last finite position counts.
"""

from __future__ import annotations

import numpy as np

from .base import Task


class WalkTask(Task):
    name = "walk"

    def start(self, body, sims):
        p0 = body.planar_position(sims).copy()
        return {"start": p0, "position": p0.copy()}

    def on_tick(self, body, sims, state, ids, healthy, neurons):
        ok = ids[healthy]
        state["position"][ok] = body.planar_position(sims)[ok]

    def fitness(self, state):
        return np.linalg.norm(state["position"] - state["start"], axis=1)
