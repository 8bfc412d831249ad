"""The G3 network against Pribe, Grossberg & Cohen 1997."""

import numpy as np
import pytest

from evobiped.experiments.g3 import network as g3net
from evobiped.experiments.g3 import gaits
from evobiped.experiments.g3 import simulation as g3sim
from evobiped.core.errors import ConfigError, UserError


def test_inhibition_matrix_layout():
    D = g3net.quadruped_D(0.8, 0.185, 0.01, 0.15, 0.02, 0.03)
    LF, RF, LH, RH = range(4)
    assert np.all(np.diag(D) == 0.8)
    assert D[LF, RF] == D[RF, LF] == D[LH, RH] == D[RH, LH] == 0.185
    assert D[LH, LF] == D[RH, RF] == 0.15  # D2 fore -> aft inhibits the hind channel
    assert D[LF, LH] == D[RF, RH] == 0.01  # D2 aft -> fore
    assert D[RH, LF] == D[LH, RF] == 0.03  # D3 fore -> aft
    assert D[LF, RH] == D[RF, LH] == 0.02  # D3 aft -> fore


def test_table1_boundaries_belong_to_the_lower_gait():
    assert list(g3net.table1_gait([0.1, 0.17, 0.171, 0.25, 0.35, 0.351])) == [0, 0, 1, 1, 2, 3]
    assert g3net.table1_D(np.array([0.35]))[0, 0, 2] == 0.55  # pace: D2 aft->fore raised


def test_go_lags_delay_every_change():
    """With only self-inhibition the channels are independent copies: channel k is
    channel 0 shifted by its lag, for the switch-on and the later switch-off alike."""
    net = g3net.G3Network(D=tuple(map(tuple, g3net.quadruped_D(1, 0, 0, 0, 0, 0))), lags=(0.0, 0.5, 1.0, 1.5))
    tr = g3sim.simulate(net, g3sim.go_schedule([[0.2, 0.0]], [0.0, 2.0]), 6.0, dt=0.01, sample_dt=0.01)
    x = tr.x[0]
    assert x[:, 0].max() > 0.3 and x[600 - 1, 0] < 0.5 * x[200, 0]  # it rises, then decays after t = 2
    for k, lag in enumerate((0.5, 1.0, 1.5), start=1):
        s = int(round(lag / 0.01))
        assert np.all(x[:s, k] == 0)
        assert np.allclose(x[s:, k], x[:-s, 0], atol=1e-9)


def test_fig4_walk_claim1():
    """Claim 1: Fig. 4 at I = 0.1 walks (lateral sequence LF, RH, RF, LH), equal duty."""
    tr = g3sim.simulate(g3net.preset("fig4").network, g3sim.go_schedule([0.1]), 120.0)
    g = gaits.analyse_gait(tr.t, tr.x[0], t_start=70.0)
    assert (g.label, g.sequence) == ("walk", "lateral")
    assert np.all(gaits.circ_dist(g.phases, [0, 0.5, 0.75, 0.25]) < 0.01)
    assert g.period == pytest.approx(10.02, abs=0.05)
    assert np.ptp(g.duty) < 0.003 and 0.17 < np.mean(g.duty) < 0.19


def test_integrator_converges():
    """Halving dt changes the Fig. 4 walk period by < 0.1 % (measured: ~1e-5)."""
    net = g3net.preset("fig4").network
    periods = [
        gaits.analyse_gait(tr.t, tr.x[0], t_start=60).period
        for tr in (g3sim.simulate(net, g3sim.go_schedule([0.1]), 100.0, dt=dt, sample_dt=0.02) for dt in (0.01, 0.005))
    ]
    assert abs(periods[0] / periods[1] - 1) < 1e-3


#: Fig. 8A / 9 sweep, state reset per I: Table 1's ranges, boundaries in the lower gait
CLAIM2 = {0.08: "walk", 0.12: "walk", 0.17: "walk", 0.19: "trot", 0.25: "trot", 0.26: "pace", 0.35: "pace",
          0.36: "gallop", 0.45: "gallop"}


@pytest.fixture(scope="module")
def fig8a_sweep():
    return g3sim.go_sweep(g3net.preset("fig8a"), list(CLAIM2), t_run=120.0)


def test_fig8a_gait_order_claim2(fig8a_sweep):
    labels = [g.label for g in fig8a_sweep.gaits]
    assert labels == list(CLAIM2.values())
    for g in fig8a_sweep.gaits:
        tpl = {"walk": (0, 0.5, 0.75, 0.25), "trot": (0, 0.5, 0.5, 0), "pace": (0, 0.5, 0, 0.5),
               "gallop": (0, 0, 0.5, 0.5)}[g.label]
        assert np.all(gaits.circ_dist(g.phases, tpl) < 0.02)


def test_fig8a_frequency_rises_ground_time_falls_claim2(fig8a_sweep):
    f = np.array([g.frequency for g in fig8a_sweep.gaits])
    assert np.all(np.diff(f) > 0)
    assert f[0] == pytest.approx(0.0967, abs=0.002) and f[-1] == pytest.approx(0.2476, abs=0.003)
    ground = np.array([(1 - np.mean(g.duty)) * g.period for g in fig8a_sweep.gaits])  # time down per cycle
    assert np.all(np.diff(ground) < 0)


def test_human_walk_and_run_claim4():
    """Claim 4 (tuned lags, see docs/g3.md): same phases, duty < 0.23 walking, > 0.31 running,
    overlapping frequencies.  The run is entered from the walk (Fig. 10's protocol)."""
    levels = [0.06, 0.1, 0.14, 0.16, 0.2, 0.26]
    s = g3sim.go_sweep(g3net.preset("human-lagged"), levels, from_go=0.1, switch_at=30.0, t_run=90.0)
    walk, run = s.gaits[:3], s.gaits[3:]
    for g in s.gaits:
        assert (g.label, g.sequence) == ("walk", "lateral")
    assert max(max(g.duty) for g in walk) < 0.23
    assert min(min(g.duty) for g in run) > 0.31
    assert min(g.frequency for g in run) < max(g.frequency for g in walk)


def test_human_faithful_lags_pronk_instead_of_run():
    """With Fig. 4's own lags the step from the walk to I = 0.15 ends in a pronk (not the run)."""
    s = g3sim.go_sweep(g3net.preset("human"), [0.1, 0.15], from_go=0.1, switch_at=30.0, t_run=90.0)
    assert [g.label for g in s.gaits] == ["walk", "pronk"]
    assert s.gaits[0].duty[0] < 0.23 and s.gaits[1].duty[0] < 0.31


def test_bad_arguments():
    with pytest.raises(ConfigError, match="unknown G3 preset 'cat'"):
        g3net.preset("cat")
    with pytest.raises(UserError, match=">= 0"):
        g3sim.go_schedule([-0.1])
    with pytest.raises(ConfigError, match="no GO levels"):
        g3sim.go_sweep(g3net.preset("fig4"), [])
    with pytest.raises(ConfigError, match="lags"):
        g3net.G3Network(D=(), lags=(), delta=())


# ------------------------------------------------------------------ the G3 controller
class _Actions:
    """Listener keeping every tick's action ``(P, n)``."""

    def __init__(self):
        self.actions = []

    def start(self, episode, sims):
        pass

    def tick(self, t, sims, ids, neurons, action, task_state):
        self.actions.append(action.copy())

    def end(self, result):
        pass


def _predicted_period_s(ctrl, D, go):
    """Period (s) of the same network integrated on its own by g3sim.simulate."""
    net = g3net.G3Network(cells=ctrl.cells, D=tuple(map(tuple, D)), lags=tuple(ctrl.lag_steps * ctrl.h),
                          delta=(0.0,) * ctrl.n)
    tr = g3sim.simulate(net, g3sim.go_schedule([go]), 60.0, dt=0.01, sample_dt=0.01)
    return gaits.analyse_gait(tr.t, tr.x[0], t_start=30.0).period / ctrl.time_scale


def test_g3_controller_drives_reil_body_at_the_network_frequency():
    """The Reil body's PD targets oscillate at the network's own frequency, and turning
    the GO knob from 0.1 to 0.2 at t = 10 s speeds the rhythm up as predicted."""
    from evobiped.episode import EpisodeConfig

    cfg = EpisodeConfig(body="reil", controller="g3", seconds=20.0,
                        body_options={"fall_height": 1e-3, "fall_tilt": np.pi},
                        controller_options={"go": [[0.0, 0.1], [10.0, 0.2]]})
    ep = cfg.build()
    ctrl = ep.controller
    lay = ctrl.layout
    assert lay.size == 6 + 30 + 6 + 6 and ctrl.substeps == 4
    g = lay.init_mean.copy()
    g[lay.slices()["gain"]] = 1.0
    g[lay.slices()["offset"]] = 0.2
    rec = _Actions()
    res = ep.run(g, listener=rec)
    assert not res.fell[0]
    a = np.array(rec.actions)[:, 0, :]  # (ticks, 6) PD targets, rad
    t = np.arange(1, len(a) + 1) * ctrl.dt
    lo, hi = ep.low, ep.high
    o = (a - lo) / (hi - lo)  # back to the unit outputs o = 0.2 + x
    D = ctrl.decode(g)["D"][0]
    for go, (t0, t1) in ((0.1, (4.0, 10.0)), (0.2, (14.0, 20.0))):
        on = gaits.upward_crossings(t, o[:, 0], 0.2 + 0.33)
        on = on[(on > t0) & (on < t1)]
        measured = np.median(np.diff(on))
        assert measured == pytest.approx(_predicted_period_s(ctrl, D, go), rel=0.01)
    periods = [np.median(np.diff(gaits.upward_crossings(t[m], o[m, 0], 0.53))) for m in (t < 10, t > 12)]
    assert periods[1] < 0.75 * periods[0]  # measured 0.93 s -> 0.63 s


def test_g3_controller_bad_options():
    from evobiped.episode import EpisodeConfig

    for opts, msg in (({"go": -0.1}, ">= 0"), ({"go": []}, "empty"), ({"go": [[1.0, 0.1], [0.5, 0.2]]}, "increase"),
                      ({"time_scale": 0}, "> 0")):
        with pytest.raises(ConfigError, match=msg):
            EpisodeConfig(body="reil", controller="g3", controller_options=opts).build()


# ------------------------------------------------------------------ the CLI
def test_cli_g3_json_and_figures(tmp_path, capsys):
    import json

    from evobiped.cli import main

    assert main(["g3", "fig4", "--go", "0.1", "--t-run", "100", "--json", "--out", str(tmp_path)]) == 0
    out = json.loads(capsys.readouterr().out)
    (row,) = out["levels"]
    assert (row["go"], row["label"], row["sequence"]) == (0.1, "walk", "lateral")
    assert row["period"] == pytest.approx(10.02, abs=0.05)
    assert sorted(p.rsplit("/", 1)[1] for p in out["files"]) == ["g3_fig4_diagrams.png", "g3_fig4_run.png"]
    assert all((tmp_path / p.rsplit("/", 1)[1]).stat().st_size > 10_000 for p in out["files"])


def test_cli_g3_reproduce_hands_the_folder_step_and_t_run_to_the_reproduction(tmp_path, monkeypatch):
    """``evobiped g3 --reproduce DIR``: the paper's defaults (step 0.01, 200 per level) unless --step/--t-run say
    otherwise."""
    from evobiped.cli import main
    from evobiped.experiments.g3 import g3_reproduce

    calls = []
    monkeypatch.setattr(g3_reproduce, "reproduce_g3", lambda out, step, t_run, say=None:
                        calls.append((out, step, t_run)))
    out = str(tmp_path / "made" / "g3")
    assert main(["g3", "--reproduce", out]) == 0
    assert main(["g3", "--reproduce", out, "--step", "0.05", "--t-run", "80"]) == 0
    assert calls == [(out, 0.01, 200.0), (out, 0.05, 80.0)] and (tmp_path / "made" / "g3").is_dir()


def test_reproduce_ranges_are_contiguous_runs_of_one_gait():
    from evobiped.experiments.g3.g3_reproduce import ranges

    assert ranges([0.1, 0.2, 0.3, 0.4], ["walk", "walk", "trot", "walk"]) == [["walk", 0.1, 0.2], ["trot", 0.3, 0.3],
                                                                              ["walk", 0.4, 0.4]]


@pytest.mark.parametrize(
    "argv, msg",
    [
        (["g3", "cat"], "unknown G3 preset 'cat'"),
        (["g3", "fig4", "--go", "-0.1"], "GO levels must be >= 0"),
        (["g3", "fig4", "--channels", ","], "channel list is empty"),
        (["g3", "fig4", "--channels", "LF,XX"], "unknown channel 'XX'"),
        (["g3", "fig4", "--sweep", "0.3", "0.1", "0.1"], "START <= STOP"),
    ],
)
def test_cli_g3_bad_arguments(argv, msg, capsys):
    from evobiped.cli import main

    assert main(argv) == 2
    err = capsys.readouterr().err
    assert msg in err and err.count("\n") == 1


def test_fig8b_walk_to_pace_within_about_a_cycle():
    """Claim 3: I 0.1 -> 0.35 at t = 25 gives a steady pace from the second cycle after the switch."""
    tr = g3sim.simulate(g3net.preset("fig8a").network, g3sim.go_schedule([[0.1, 0.35]], [0.0, 25.0]), 50.0)
    starts, ph = gaits.cycle_phases(tr.t, tr.x[0])
    labels = [gaits.classify(q)[0] for q in ph]
    after = starts >= 25.0
    first_pace = np.flatnonzero(after)[1]
    assert all(lab == "pace" for lab in labels[first_pace:]) and len(labels) - first_pace >= 3
    assert (starts[first_pace] - 25.0) / np.median(np.diff(starts[first_pace:])) < 1.2  # measured 1.10


def test_g3_controller_rows_do_not_depend_on_the_batch():
    from evobiped.episode import EpisodeConfig

    ep = EpisodeConfig(body="reil", controller="g3", seconds=1.0).build()
    lay = ep.controller.layout
    g = lay.sample(np.random.default_rng(3), 3)
    alone = ep.run(g[1]).fitness[0]
    assert ep.run(g).fitness[1] == alone


def test_every_published_parameter_set_takes_the_cell_constants_the_controller_names():
    """The G3 controller's ``preset`` option names cell constants (the core's CELLS); each published
    parameter set of the experiment uses exactly those constants."""
    from evobiped.controllers.g3_network import CELLS, Shunting

    assert set(g3net.PRESETS) == set(CELLS)
    for name, p in g3net.PRESETS.items():
        assert p.network.cells == CELLS[name]
    assert CELLS["fig5b"] == Shunting(B=1.05) and CELLS["fig4"] == Shunting()

