"""Taga et al. 1991's experiments, each a :class:`~.walking.TagaWalker` advanced in pieces: steady walking (claims 1-2),
Fig. 7's pushes, a switch of the ground (claim 6), Fig. 11's u_0 sweeps."""

from __future__ import annotations

import numpy as np

from .stride import per_stride
from .walking import TagaWalker, set_push


def steady(u0, *, seconds: float = 20.0, window: float = 10.0, **options) -> tuple[TagaWalker, list[dict]]:
    """Run from Appendix E's initial condition; metrics over the last ``window`` s."""
    w = TagaWalker(u0, **options)
    w.advance(seconds)
    return w, w.metrics(t_start=seconds - window)


def push(
    target: str,
    force: float,
    delays=(0.05,),
    *,
    u0: float = 5.5,
    before: float = 10.0,
    duration: float = 0.2,
    after: float = 8.0,
    tolerance: float = 0.05,
    **options,
) -> tuple[TagaWalker, list[dict]]:
    """Fig. 7: walk ``before`` s, then push ``target`` forward with ``force`` N for ``duration`` s.

    Walker p is pushed ``delays[p]`` s after the first liftoff of the right
    foot after ``before`` (a right-shank push with a short delay hits the
    swinging shank).  Per walker: push time, fell/when, the median stride
    length and cycle duration of the strides before the push, every stride
    after it, and the strides until all later ones are within ``tolerance``
    (relative) of the pre-push values (None if never).  A walker that fell
    before its push has ``t_push`` None; without strides before the push the
    pre-push values are nan.
    """
    delays = np.asarray(delays, float)
    w = TagaWalker(np.full(len(delays), u0), **options)
    w.advance(before)
    step = w.body.timestep
    for _ in range(int(round(2.0 / step))):  # to the right foot's liftoff
        was = w.body.sensors(w.sims)["ground_contact"][0, 0]
        w.advance(step)
        if was > 0 and w.body.sensors(w.sims)["ground_contact"][0, 0] == 0:
            break
    starts = w.time + delays
    t_end = starts.max() + duration + after
    on = np.zeros(len(delays), bool)
    given = np.zeros(len(delays), bool)  # the push acted on the walker for at least one step
    while w.alive.any() and w.time < t_end - step / 2:  # an all-down batch stops its clock
        t = w.time
        want = (t >= starts - step / 2) & (t < starts + duration - step / 2)
        for i in np.flatnonzero(want != on):
            set_push(w.sims, np.array([i]), target if want[i] else "none", force if want[i] else 0.0)
        on = want
        given |= want & w.alive
        w.advance(step)
    a = w.trace.arrays()
    rows = []
    for p in range(w.P):
        s, L, D = per_stride(a["t"], a["contact"][:, p], a["ankle"][:, p, :, 0])
        pre, post = (s < starts[p] - 1.5) & (s > before - 5.0), s > starts[p]
        refL, refD = (float(np.median(L[pre])), float(np.median(D[pre]))) if pre.any() else (np.nan, np.nan)
        ok = (np.abs(L[post] / refL - 1) < tolerance) & (np.abs(D[post] / refD - 1) < tolerance)
        fell = bool(not w.alive[p])
        recovered = None if fell else next((i for i in range(len(ok)) if ok[i:].all() and len(ok) - i >= 3), None)
        rows.append(
            dict(
                target=target,
                force=float(force),
                delay=float(delays[p]),
                t_push=float(starts[p]) if given[p] else None,
                fell=fell,
                fell_at=float(w.fell_at[p]) if fell else None,
                stride_length_before=refL,
                cycle_duration_before=refD,
                strides_after=[(float(x), float(y)) for x, y in zip(L[post], D[post])],
                strides_to_recover=recovered,
            )
        )
    return w, rows


def ground_switch(kg, bg, *, u0: float = 5.5, before: float = 10.0, after: float = 15.0, window: float = 10.0,
                  **options) -> list[dict]:
    """Claim 6, second reading: walk ``before`` s on the nominal ground (Appendix D), then
    switch walker p to ground (kg[p], bg[p]) and walk ``after`` s more; metrics over the last ``window`` s."""
    kg, bg = np.asarray(kg, float), np.asarray(bg, float)
    w = TagaWalker(np.full(len(kg), u0), **options)
    w.advance(before)
    w.set_ground(kg, bg)
    w.advance(after)
    rows = w.metrics(t_start=w.time - window)
    for r, k, b in zip(rows, kg, bg):
        r.update(kg=float(k), bg=float(b))
    return rows


def u0_sweep(u0_values, *, settle: float = 8.0, window: float = 4.0, first: float = 20.0, **options) -> list[dict]:
    """Fig. 11: step u_0 through ``u0_values``, each step starting from the previous steady state.

    The first value runs ``first`` s from Appendix E's initial condition, every
    later one ``settle`` s; metrics over the last ``window`` s of each.
    A fall ends the sweep (later values are reported as fell).
    """
    w = TagaWalker(u0_values[0], **options)
    rows = []
    for i, u in enumerate(u0_values):
        w.set_u0(u)
        dur = first if i == 0 else settle
        w.advance(dur)
        m = w.metrics(t_start=w.time - window)[0]
        m["u0"] = float(u)
        rows.append(m)
    return rows
