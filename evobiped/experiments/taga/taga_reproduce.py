"""Every table and figure of Taga, Yamaguchi & Shimizu 1991 (Figs. 5-11), published parameters: ``evobiped taga
--reproduce DIR``.

Writes into DIR: ``taga_results.json`` (every number), ``summary.md`` (the
tables), and PNG figures: stick figures of walking and running (Figs. 5, 9),
one steady cycle of each, pushes (Fig. 7), uphill walking (Fig. 8), neuron
activity walking vs isolated (Fig. 6) and the u0 bifurcation diagrams
(Fig. 11).  Progress lines go to stderr; docs/taga.md gives the running times.
``quick`` runs every part on coarser grids (fewer u0 values, push phases,
slopes and ground parameters, no physics-step halving) to check the pipeline,
not the numbers.  The files are one set (:func:`~evobiped.files.rundir.output_set.output_set`, the files
:func:`taga_outputs` names, quick or not): the previous reproduction's are removed first, and one cut short is said by
the next.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from ...core.fileio import atomic_write
from ...core.progress import Progress
from ...files.rundir.output_set import output_set
from . import generator, protocols
from . import taga_figures as fig
from .stride import contact_onsets

NEURONS = ["RH f", "RH e", "RK f", "RK e", "RA f", "RA e", "LH f", "LH e", "LK f", "LK e", "LA f", "LA e"]


def log(msg: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", flush=True)


def fmt(rows: list[dict], keys: list[str]) -> str:
    head = "| " + " | ".join(keys) + " |\n|" + "---|" * len(keys) + "\n"

    def cell(v):
        if isinstance(v, float):
            return "-" if not np.isfinite(v) else (f"{v:.2g}" if 0 < abs(v) < 0.01 else f"{v:.3f}")
        return "-" if v is None else str(v)

    return head + "".join("| " + " | ".join(cell(r.get(k)) for k in keys) + " |\n" for r in rows)


METRIC_KEYS = ["u0", "gait", "fell_at", "strides", "stride_length", "cycle_duration", "speed", "double_support",
               "flight", "hip_min", "hip_max"]


def one_cycle(tr: dict, p: int, after: float) -> tuple[float, float]:
    td = contact_onsets(tr["contact"][:, p, 0])
    td = td[tr["t"][td] > after]
    return float(tr["t"][td[0]]), float(tr["t"][td[1]])


#: the slopes of claim 5 in %, and those of a quick run
SLOPES, QUICK_SLOPES = (2, 3, 4, 5, 6, 8, -1, -2, -4, -6, -10), (4, 6, 8, -2, -6)
#: the bodies pushed in claim 4 (Fig. 7) and their forces, N
PUSHES = (("right_shank", 200.0), ("hip", 288.0))


def taga_outputs(out: str | Path) -> list[Path]:
    """Every file :func:`reproduce_taga` may write into ``out``, quick or not."""
    out = Path(out)
    names = ["taga_results.json", "summary.md", "fig5a_walk_u5.5.png", "fig5b_walk_cycle.png", "fig9a_run_u7.5.png",
             "fig9b_run_cycle.png", "fig6_activity.png", "fig11_bifurcation.png",
             *(f"fig7_push_{target}.png" for target, _ in PUSHES),
             *(f"fig8_uphill_{s}pct.png" for s in sorted({*SLOPES, *QUICK_SLOPES}) if s > 0)]
    return [out / n for n in names]


def reproduce_taga(out: str | Path, quick: bool = False, quiet: bool = False, say=None) -> None:
    """Run every experiment of the paper and write its tables and figures into ``out`` (made if missing) as one
    set, the previous one removed first; ``say(line)`` hears that the previous reproduction was cut short."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with output_set("taga reproduction", taga_outputs(out), say=say):
        _experiments(out, quick, quiet)


def _experiments(out: Path, quick: bool, quiet: bool) -> None:
    """The experiments of :func:`reproduce_taga`, each figure written into ``out`` as it is drawn."""

    def progress(what: str, seconds: float):
        """A ``TagaWalker(progress=...)`` callback: progress lines over ``seconds`` of simulated time."""
        return Progress(what, seconds, "s simulated", quiet=quiet).update

    R: dict = {}
    md = ["# Taga et al. 1991 reproduction (published parameters, preset `taga`)\n"]
    step = 0.5 if quick else 0.25

    # ---- claims 1, 2: walking at 5.5, running from Appendix E; u0 scan from the initial state
    log("claims 1-2: walking and running from Appendix E")
    scan = np.round(np.arange(3.0, 10.0 + 1e-9, step), 2)
    w, rows = protocols.steady(scan, seconds=20.0, window=10.0, progress=progress("claims 1-2", 20.0))
    R["from_initial_state"] = rows
    md += ["## Every u0 from Appendix E's initial condition (20 s, metrics over the last 10 s)\n",
           fmt(rows, METRIC_KEYS)]
    tr = w.trace.arrays()
    iw, ir = int(np.flatnonzero(scan == 5.5)[0]), int(np.flatnonzero(scan == 7.5)[0])
    fig.taga_stick_figure(out / "fig5a_walk_u5.5.png", tr, p=iw, t1=10.0,
                          title="walking, u0 = 5.5 (traced every 0.1 s)")
    a, b = one_cycle(tr, iw, 15.0)
    fig.cycle_figure(out / "fig5b_walk_cycle.png", tr, a, b, p=iw,
                     title=f"one steady walking cycle, u0 = 5.5 ({b - a:.2f} s, every 0.02 s)")
    fig.taga_stick_figure(out / "fig9a_run_u7.5.png", tr, p=ir, t1=10.0, title="running, u0 = 7.5 (traced every 0.1 s)")
    a, b = one_cycle(tr, ir, 15.0)
    fig.cycle_figure(out / "fig9b_run_cycle.png", tr, a, b, p=ir,
                     title=f"one steady running cycle, u0 = 7.5 ({b - a:.2f} s, every 0.02 s)")

    # ---- claim 7: isolated generator vs walking rhythm; Fig. 6
    log("claim 7: isolated rhythm generator")
    walking = generator.walking_hip_period(w, t_start=10.0, p=iw)
    iso = {f"{u:g}": generator.isolated_period(u) for u in (4.0, 5.5, 7.5)}
    R["isolated"] = {"walking_hip_period_u5.5": walking, "isolated_hip_period": iso}
    md += [f"## Isolated generator (Feed = 0)\n\nhip-oscillator period walking at u0 = 5.5: {walking:.3f} s; "
           f"isolated: " + ", ".join(f"u0 = {k}: {v:.3f} s" for k, v in iso.items()) + "\n"]
    ti_t, ti_u = generator.isolated_activity(5.5, seconds=12.0)
    order = np.r_[0:6, 6:12]
    sel_w = (tr["t"] >= 16) & (tr["t"] <= 20)
    sel_i = (ti_t >= 8) & (ti_t <= 12)
    fig.activity_figure(out / "fig6_activity.png", [
        ("A walking, u0 = 5.5", tr["t"][sel_w], tr["u"][sel_w, iw][:, order]),
        ("B isolated (Feed = 0), u0 = 5.5", ti_t[sel_i], ti_u[sel_i][:, order])], NEURONS)

    # ---- claim 3: hysteresis sweeps (Fig. 11)
    log("claim 3: u0 sweeps up and down")
    up_vals = list(np.round(np.arange(5.5, 9.0 + 1e-9, step), 2))
    down_vals = list(np.round(np.arange(7.75 if not quick else 7.5, 3.0 - 1e-9, -step), 2))
    up = protocols.u0_sweep(up_vals, progress=progress("sweep up", 20.0 + 8.0 * (len(up_vals) - 1)))
    down = protocols.u0_sweep(down_vals, progress=progress("sweep down", 20.0 + 8.0 * (len(down_vals) - 1)))
    R["sweep_up"], R["sweep_down"] = up, down
    md += ["## u0 swept up from walking (each step continues from the previous state; 8 s per step, last 4 s)\n",
           fmt(up, METRIC_KEYS), "## u0 swept down from running\n", fmt(down, METRIC_KEYS)]
    fig.bifurcation_figure(out / "fig11_bifurcation.png", up, down,
                           title="Fig. 11: filled = sweep up, open = sweep down; squares walk, diamonds run")

    # ---- claim 4: pushes at phases of the cycle (Fig. 7)
    log("claim 4: pushes")
    delays = np.arange(0.0, 1.12, 0.2 if quick else 0.1)
    for target, force in PUSHES:
        wp, prow = protocols.push(target, force, delays, before=10.0, after=8.0,
                                  progress=progress(f"push {target}", 21.3))
        R[f"push_{target}"] = prow
        keys = ["delay", "t_push", "fell", "fell_at", "stride_length_before", "strides_to_recover"]
        for r in prow:
            r["first_strides_after"] = "; ".join(f"{L:.2f} m/{D:.2f} s" for L, D in r["strides_after"][:3])
        md += [f"## Push: {target}, {force:g} N forward for 0.2 s, at `delay` s after the right foot's liftoff\n",
               fmt(prow, keys + ["first_strides_after"])]
        good = next((p for p, r in enumerate(prow) if not r["fell"]), 0)
        tp = wp.trace.arrays()
        fig.taga_stick_figure(out / f"fig7_push_{target}.png", tp, p=good, t0=prow[good]["t_push"] - 2.0,
                              t1=prow[good]["t_push"] + 5.0,
                         title=f"push {target} {force:g} N for 0.2 s at t = {prow[good]['t_push']:.2f} s (triangle)",
                              marks=[prow[good]["t_push"]])

    # ---- claim 5: slopes (start at x = 5 m, after ~4 s of level walking)
    log("claim 5: slopes")
    slopes = list(QUICK_SLOPES if quick else SLOPES)
    srows = []
    for s in slopes:
        ws, (m,) = protocols.steady(5.5, seconds=25.0, window=10.0, slope=s / 100, slope_start=5.0,
                                    progress=progress(f"slope {s} %", 25.0))
        m["slope_pct"] = s
        m["distance"] = float(ws.trace.arrays()["hip"][-1, 0, 0])
        srows.append(m)
        if s > 0:
            tr_s = ws.trace.arrays()
            t_on = float(tr_s["t"][np.argmax(tr_s["hip"][:, 0, 0] > 5.0)])
            state = f"fell at {m['fell_at']:.1f} s" if m["fell"] else "walks"
            fig.taga_stick_figure(out / f"fig8_uphill_{s}pct.png", tr_s, t0=t_on,
                                  t1=min(t_on + 8.0, float(tr_s["t"][-1])),
                             title=f"{s} % uphill from x = 5 m, u0 = 5.5: {state}", terrain=ws.body.terrain)
    R["slopes"] = srows
    md += ["## Slopes (level to x = 5 m, then the slope; 25 s, metrics over the last 10 s)\n",
           fmt(srows, ["slope_pct", "distance"] + METRIC_KEYS[1:])]

    # ---- claim 6: ground parameters; the explicit damper needs dt <= 0.5 ms * 2e3 / b_g
    log("claim 6: ground parameters")
    grows = []
    if quick:  # the nominal step only (the stiff grounds need 5-10x smaller steps)
        kgs, ground_steps = (5e3, 1e4, 4e4), ((0.0005, [4e2, 1e3, 2e3]),)
    else:
        kgs, ground_steps = (5e3, 8e3, 1e4, 2e4, 4e4), ((0.0005, [4e2, 8e2, 1e3, 2e3]), (0.0001, [1e4]),
                                                        (0.00005, [2e4]))
    for dt, sel in ground_steps:
        grid = [(kg, bg) for bg in sel for kg in kgs]
        kg_, bg_ = np.array(grid).T
        _, rows_ = protocols.steady(np.full(len(grid), 5.5), seconds=20.0, window=10.0, kg=kg_, bg=bg_, timestep=dt,
                                    record_every=int(round(0.002 / dt)),
                             progress=progress(f"ground, step {dt * 1000:g} ms", 20.0))
        for (kg, bg), m in zip(grid, rows_):
            m.update(kg=kg, bg=bg, timestep=dt)
            grows.append(m)
        log(f"  b_g {sel}: " + ", ".join(f"{m['kg']:g}/{m['bg']:g} {m['gait']}" for m in rows_))
    R["ground"] = grows
    md += ["## Ground parameters from Appendix E's initial state (u0 = 5.5, 20 s; physics step 0.5 ms, smaller for b_g "
           "> 2000)\n", fmt(grows, ["kg", "bg", "timestep"] + METRIC_KEYS[1:])]
    swrows = []
    for dt, sel in ground_steps:
        grid = [(kg, bg) for bg in sel for kg in kgs]
        kg_, bg_ = np.array(grid).T
        rows_ = protocols.ground_switch(kg_, bg_, timestep=dt, record_every=int(round(0.002 / dt)),
                                 progress=progress(f"switched ground, step {dt * 1000:g} ms", 25.0))
        for m in rows_:
            m["timestep"] = dt
        swrows += rows_
        log(f"  switched, b_g {sel}: " + ", ".join(f"{m['kg']:g}/{m['bg']:g} {m['gait']}" for m in rows_))
    R["ground_switch"] = swrows
    md += ["## Ground parameters switched after 10 s of steady walking on the nominal ground (15 s more, last 10 s)\n",
           fmt(swrows, ["kg", "bg", "timestep"] + METRIC_KEYS[1:])]

    # ---- convergence of the physics step
    log("convergence: halving the physics step" + (" (skipped with --quick)" if quick else ""))
    conv = []
    for dt in () if quick else (0.0005, 0.00025):
        _, rows_ = protocols.steady([5.5, 7.5], seconds=20.0, window=10.0, timestep=dt,
                                    record_every=int(round(0.002 / dt)),
                             progress=progress(f"convergence, step {dt * 1000:g} ms", 20.0))
        for m in rows_:
            m["timestep"] = dt
        conv += rows_
    R["convergence"] = conv
    md += ["## Convergence (physics step halved)\n", fmt(conv, ["timestep"] + METRIC_KEYS)]

    atomic_write(out / "taga_results.json", json.dumps(R, indent=1, default=float))
    atomic_write(out / "summary.md", "\n".join(md))
    log(f"wrote {out}/summary.md, taga_results.json and the PNGs")

