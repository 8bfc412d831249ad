"""Pribe, Grossberg & Cohen 1997 (G3) checked claim by claim: ``evobiped g3 --reproduce DIR``; see docs/g3.md.

Writes summary.json, one CSV per sweep and the PNG figures to DIR, and prints
the numbers docs/g3.md quotes.  Takes ~1.5 minutes on one core.  The files are one
set (:func:`~evobiped.files.rundir.output_set.output_set`, the files :func:`g3_outputs` names): the previous
reproduction's are removed first, and a reproduction cut short is said by the next one.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from ...core.fileio import atomic_write
from ...files.rundir.output_set import output_set
from . import gaits
from . import network as g3net
from . import simulation as g3sim
from .g3_figures import run_figure, sweep_figures, sweep_files


def ranges(levels, labels):
    """Contiguous runs of one label: [(label, first I, last I), ...]."""
    out = []
    for lv, lab in zip(levels, labels):
        if out and out[-1][0] == lab:
            out[-1][2] = float(lv)
        else:
            out.append([lab, float(lv), float(lv)])
    return out


def save_sweep(out: Path, name: str, s: g3sim.GoSweep, title: str) -> dict:
    rows = [{"go": float(lv), **g.as_dict()} for lv, g in zip(s.levels, s.gaits)]
    fh = io.StringIO()
    w = csv.writer(fh)
    w.writerow(["go", "label", "sequence", "frequency", "period", "ph_LF", "ph_RF", "ph_LH", "ph_RH", "duty_mean",
                "steps_LF", "steps_RF", "steps_LH", "steps_RH", "first_cycle", "settle_time"])
    for r in rows:
        w.writerow([r["go"], r["label"], r["sequence"], r["frequency"], r["period"], *r["phases"], np.mean(r["duty"]),
                    *r["steps"], r["transient_label"], r["settle_time"]])
    atomic_write(out / f"{name}.csv", fh.getvalue())
    sweep_figures(out, name, s, [0, 1, 2, 3], g3net.LIMBS, title=title)
    labels = [g.label for g in s.gaits]
    osc = [g for g in s.gaits if g.oscillating]
    return {
        "ranges": ranges(s.levels, labels),
        "frequency": [[float(lv), g.frequency] for lv, g in zip(s.levels, s.gaits)],
        "duty": [[float(lv), float(np.mean(g.duty))] for lv, g in zip(s.levels, s.gaits)],
        "frequency_monotone": bool(np.all(np.diff([g.frequency for g in osc]) > 0)),
    }


#: the human presets of claim 4, and the sweeps each starts from
HUMAN, HUMAN_MODES = ("human", "human-lagged"), ("reset", "from_walk")
#: the symmetric presets of claim 5 (and Fig. 7's)
SYMMETRIC = ("fig5a", "fig5b", "fig7")


def g3_outputs(out: str | Path) -> list[Path]:
    """Every file :func:`reproduce_g3` may write into ``out``, whatever its ``step``: summary.json, each sweep's CSV
    and figures, the single runs' figures."""
    out = Path(out)
    sweeps = ["claim2_fig8a_sweep", *(f"claim4_{n}_{m}" for n in HUMAN for m in HUMAN_MODES),
              *(f"claim5_{n}_sweep" for n in SYMMETRIC)]
    return [out / "summary.json", out / "claim1_fig4_walk.png", out / "claim3_fig8b_walk_to_pace.png",
            *(out / f"claim4_{n}_fig10.png" for n in HUMAN),
            *(p for s in sweeps for p in (out / f"{s}.csv", *sweep_files(out, s)))]


def reproduce_g3(out: str | Path, step: float = 0.01, t_run: float = 200.0, say=None) -> None:
    """Every claim: the GO sweeps in increments of ``step`` (paper: 0.01), ``t_run`` time units per GO level of the
    quadruped sweeps (steady state: the last 40 %); writes into ``out`` (made if missing) as one set, the previous
    one removed first; ``say(line)`` hears that the previous reproduction was cut short."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with output_set("g3 reproduction", g3_outputs(out), say=say):
        _claims(out, step, t_run)


def _claims(out: Path, step: float, t_run: float) -> None:
    """The claims of :func:`reproduce_g3`, each written into ``out`` as it is checked."""
    levels = np.round(np.arange(0.05, 0.5 + 1e-9, step), 6)
    summary: dict = {}

    # claim 1: Fig. 4 walk
    p = g3net.preset("fig4")
    tr = g3sim.simulate(p.network, g3sim.go_schedule([0.1]), p.t_run)
    g = gaits.analyse_gait(tr.t, tr.x[0], t_start=0.6 * p.t_run)
    run_figure(out / "claim1_fig4_walk.png", tr.t, tr.x[0], g3net.LIMBS,
               title=f"Fig. 4 parameters, I = 0.1: {g.label} ({g.sequence})", go=tr.go[0])
    summary["claim1"] = g.as_dict()
    print(f"claim 1: {g.label} {g.sequence}, period {g.period:.3f}, phases {np.round(g.phases, 3)}, duty "
          f"{np.round(g.duty, 3)}, first cycle {g.transient_label}, settled at t = {g.settle_time:.1f}")

    # claim 2: Fig. 8A / 9 sweep, reset per I
    s = g3sim.go_sweep(g3net.preset("fig8a"), levels, t_run=t_run)
    c2 = save_sweep(out, "claim2_fig8a_sweep", s, "Fig. 8A/9: Table 1 modulation, reset per I")
    ok = [g for g in s.gaits if g.oscillating]
    ground = np.array([(1 - np.mean(g.duty)) * g.period for g in ok])
    c2["ground_time_per_cycle_monotone"] = bool(np.all(np.diff(ground) < 0))
    c2["ground_fraction_by_gait"] = {lab: float(np.mean([1 - np.mean(g.duty) for g in ok if g.label == lab]))
                                     for lab in ("walk", "trot", "pace", "gallop")}
    summary["claim2"] = c2
    print("claim 2 ranges:", [(a, round(b, 3), round(c, 3)) for a, b, c in c2["ranges"]])
    print(f"  frequency monotone: {c2['frequency_monotone']} ({ok[0].frequency:.4f} .. {ok[-1].frequency:.4f}); "
          f"ground time per cycle monotone decreasing: {c2['ground_time_per_cycle_monotone']} ({ground[0]:.2f} .. "
          f"{ground[-1]:.2f}); ground fraction by gait: "
          f"{ {k: round(v, 3) for k, v in c2['ground_fraction_by_gait'].items()} }")

    # claim 3: Fig. 8B, walk then pace
    tr = g3sim.simulate(g3net.preset("fig8a").network, g3sim.go_schedule([[0.1, 0.35]], [0.0, 25.0]), 50.0)
    starts, ph = gaits.cycle_phases(tr.t, tr.x[0])
    labs = [gaits.classify(q)[0] for q in ph]
    after = [i for i in range(len(starts)) if starts[i] >= 25.0]
    first_pace = next(i for i in after if all(labs[j] == "pace" for j in range(i, len(labs))))
    pace_period = float(np.median(np.diff(starts[first_pace:])))
    onset_before = {k: [float(v) for v in np.round(gaits.upward_crossings(tr.t,
                                                                          tr.x[0, :,
                                                                               i])[gaits.upward_crossings(tr.t, tr.x[
                                                                                   0, :, i]) < 25], 2)] for i,
                    k in enumerate(g3net.LIMBS)}
    summary["claim3"] = {"cycles": [[float(a), lab] for a, lab in zip(starts, labs)],
                         "pace_from": float(starts[first_pace]),
                         "pace_period": pace_period, "delay_cycles": (float(starts[first_pace]) - 25.0) / pace_period,
                         "onsets_before_switch": onset_before}
    run_figure(out / "claim3_fig8b_walk_to_pace.png", tr.t, tr.x[0], g3net.LIMBS,
               title="Fig. 8B: I 0.1 -> 0.35 at t = 25", go=tr.go[0])
    print(f"claim 3: onsets before the switch {onset_before}; steady pace from t = {starts[first_pace]:.2f} "
          f"({summary['claim3']['delay_cycles']:.2f} pace periods of {pace_period:.2f} after the switch)")

    # claim 4: human walk and run (faithful, then the tuned lags)
    hl = np.round(np.arange(0.05, 0.30 + 1e-9, step), 6)
    c4 = {}
    for name in HUMAN:
        for mode, kw in ((HUMAN_MODES[0], {}), (HUMAN_MODES[1], {"from_go": 0.1, "switch_at": 30.0})):
            s = g3sim.go_sweep(g3net.preset(name), hl, **kw)
            r = save_sweep(out, f"claim4_{name}_{mode}", s, f"Sect. 6 {name}: "
                           + ("reset per I" if mode == "reset" else "from the walk at I = 0.1, switch at t = 30"))
            walk = [g for g in s.gaits if g.label == "walk" and max(g.duty) < 0.23]
            run = [g for g in s.gaits if g.label == "walk" and min(g.duty) > 0.31]
            r["walk_duty_max"] = max((max(g.duty) for g in walk), default=None)
            r["run_duty_min"] = min((min(g.duty) for g in run), default=None)
            r["walk_freq"] = [min((g.frequency for g in walk), default=None),
                              max((g.frequency for g in walk), default=None)]
            r["run_freq"] = [min((g.frequency for g in run), default=None),
                             max((g.frequency for g in run), default=None)]
            c4[f"{name}/{mode}"] = r
            print(f"claim 4 {name} {mode}: ranges {[(a, round(b, 3), round(c, 3)) for a, b, c in r['ranges']]}; walk "
                  f"duty max {r['walk_duty_max']}, run duty min {r['run_duty_min']}; walk freq {r['walk_freq']}, run "
                  f"freq {r['run_freq']}")
    for name in HUMAN:  # Fig. 10: walk 0.1 -> 0.15 at t = 30
        tr = g3sim.simulate(g3net.preset(name).network, g3sim.go_schedule([[0.1, 0.15]], [0.0, 30.0]), 150.0)
        g = gaits.analyse_gait(tr.t, tr.x[0], t_start=90.0)
        c4[f"{name}/fig10"] = g.as_dict()
        run_figure(out / f"claim4_{name}_fig10.png", tr.t, tr.x[0], g3net.LIMBS,
                   title=f"Fig. 10 ({name}): I 0.1 -> 0.15 at t = 30: {g.label}", go=tr.go[0])
        print(f"claim 4 {name} Fig. 10 (0.1 -> 0.15 at t = 30): {g.label}, duty {np.round(g.duty, 3)}, period "
              f"{g.period:.3f}")
    summary["claim4"] = c4

    # claim 5: Fig. 5A / 5B, symmetric unmodulated
    for name in SYMMETRIC:
        s = g3sim.go_sweep(g3net.preset(name), levels, t_run=t_run)
        r = save_sweep(out, f"claim5_{name}_sweep", s, f"{g3net.preset(name).source}, reset per I")
        summary[f"claim5_{name}" if name != "fig7" else "fig7"] = r
        print(f"{name}: ranges {[(a, round(b, 3), round(c, 3)) for a, b, c in r['ranges']]}")

    # convergence of the integrator
    conv = {}
    for name, go in (("fig4", 0.1), ("fig8a", 0.3)):
        per = []
        for dt in (0.01, 0.005, 0.0025):
            tr = g3sim.simulate(g3net.preset(name).network, g3sim.go_schedule([go]), 120.0, dt=dt, sample_dt=0.01)
            per.append(gaits.analyse_gait(tr.t, tr.x[0], t_start=60.0).period)
        conv[name] = {"dt": [0.01, 0.005, 0.0025], "period": per, "rel_change_halving_0.005": abs(per[2] / per[1] - 1)}
        print(f"convergence {name} I={go}: periods {per}, halving 0.005 -> 0.0025 changes it by "
              f"{conv[name]['rel_change_halving_0.005']:.1e}")
    summary["convergence"] = conv
    atomic_write(out / "summary.json", json.dumps(summary, indent=1))
    print(f"wrote {out}/summary.json and figures")

