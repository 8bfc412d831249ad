"""The Rerun recording and the figures, checked against the simulation.

A recording is read back with ``rerun.chunk.RrdReader`` and compared with an
independent run of the same episode (no recorder; a two-line listener that
copies the pelvis pose).  Rerun stores poses as float32, so poses are
compared at float32 precision; scalars are float64 and compared exactly.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import mujoco
import numpy as np
import pytest

from evobiped.episode import EpisodeConfig
from evobiped.record import geometry
from evobiped.record.trajectory import record

rr = pytest.importorskip("rerun")

DT = 0.02


def random_genome(layout, seed):
    r = np.random.default_rng(seed)
    return layout.sample(r)


def standing_genome(layout):
    """No connections: every output stays sigma(-alpha); targets hip pitch 0, roll 0, knee ~0."""
    g = np.zeros(layout.size)
    s = layout.slices()
    g[s["time_constants"]] = 1.0
    alpha = np.zeros(10)
    alpha[[0, 3]] = -np.log(0.448 / 0.552)  # hip pitch target 0 in [-1.3, 1.6]
    alpha[[2, 5]] = -4.0  # knee output 0.982 -> target -0.025 rad
    g[s["biases"]] = alpha
    return g


def read_rrd(path) -> dict[str, dict]:
    """entity path -> {"static": [record batches], "temporal": record batch (merged rows, by time)}."""
    out: dict[str, dict] = {}
    for ch in rr.chunk.RrdReader(path).stream():
        e = out.setdefault(ch.entity_path, {"static": [], "temporal": []})
        e["static" if ch.is_static else "temporal"].append(ch.to_record_batch())
    return out


def column(entity: dict, name: str) -> tuple[np.ndarray, list]:
    """(sim_time in s, values) of a temporal component over all chunks of an entity, time-sorted."""
    times, vals = [], []
    for rb in entity["temporal"]:
        if name not in rb.schema.names:
            continue
        times += [t.value / 1e9 for t in rb.column("sim_time")]
        vals += rb.column(name).to_pylist()
    order = np.argsort(times, kind="stable")
    return np.array(times)[order], [vals[i] for i in order]


def write_recording(episode, genome, path):
    from evobiped.record.recordings.rerun_recorder import RerunRecorder

    rec = rr.RecordingStream("test", recording_id="test")
    rec.save(path)
    listener = RerunRecorder(rec)
    result = episode.run(genome[None], listener=listener)
    rec.flush()
    rec.disconnect()
    return result, listener.trajectory


class PelvisPoses:
    """Independent reference: the pelvis pose after every tick, straight from MuJoCo's data."""

    def __init__(self):
        self.rows = []

    def start(self, episode, sims):
        self.b = episode.model.body("pelvis").id
        self.rows.append((0.0, sims.xpos[0, self.b].copy(), sims.xquat[0, self.b].copy()))

    def tick(self, t, sims, ids, neurons, action, task_state):
        self.rows.append((t, sims.xpos[0, self.b].copy(), sims.xquat[0, self.b].copy()))

    def end(self, result):
        pass


@pytest.fixture(scope="module")
def moving(tmp_path_factory):
    """A random walker over 3 s (it falls before the end), recorded and simulated independently."""
    ep = EpisodeConfig(seconds=3.0).build()
    g = random_genome(ep.controller.layout, 4)
    path = tmp_path_factory.mktemp("rec") / "moving.rrd"
    result, traj = write_recording(ep, g, path)
    ref = PelvisPoses()
    ref_result = EpisodeConfig(seconds=3.0).build().run(g[None], listener=ref)
    plain = EpisodeConfig(seconds=3.0).build().run(g[None])
    return dict(ep=ep, g=g, result=result, traj=traj, ref=ref, ref_result=ref_result, plain=plain, rrd=read_rrd(path))


def test_recorder_does_not_change_the_simulation(moving):
    r, plain = moving["result"], moving["plain"]
    assert r.fitness[0] == plain.fitness[0]  # bit for bit
    assert r.end_time[0] == plain.end_time[0]
    assert bool(r.fell[0]) == bool(plain.fell[0])
    np.testing.assert_array_equal(r.end_position, plain.end_position)


def test_pelvis_pose_in_the_recording_equals_the_simulated_one(moving):
    ticks = round(moving["result"].end_time[0] / DT)
    assert 20 < ticks < 150  # moves for a while, then falls before 3 s
    times, trans = column(moving["rrd"]["/world/bodies/pelvis"], "Transform3D:translation")
    _, quats = column(moving["rrd"]["/world/bodies/pelvis"], "Transform3D:quaternion")
    ref = moving["ref"].rows
    assert len(times) == len(ref) == ticks + 1  # t = 0 and after every tick
    np.testing.assert_allclose(times, np.arange(ticks + 1) * DT, atol=1e-9)
    for k in (0, 1, ticks // 3, 2 * ticks // 3, ticks):
        t, pos, q = ref[k]
        assert times[k] == pytest.approx(t, abs=1e-9)
        np.testing.assert_array_equal(np.array(trans[k][0], np.float32), pos.astype(np.float32))
        wxyz = np.array(quats[k][0], np.float32)[[3, 0, 1, 2]]  # Rerun xyzw -> MuJoCo wxyz
        np.testing.assert_array_equal(wxyz, q.astype(np.float32))
    # the walker really moved between the checked frames
    assert np.linalg.norm(ref[ticks][1] - ref[0][1]) > 0.2


def test_every_neuron_has_one_entry_per_tick(moving):
    rrd, traj = moving["rrd"], moving["traj"]
    ticks = round(moving["result"].end_time[0] / DT)
    neurons = sorted(p for p in rrd if p.startswith("/neurons/") and rrd[p]["temporal"])
    assert len(neurons) == 10
    assert sum(p.startswith("/neurons/motor/") for p in neurons) == 6
    assert "/neurons/motor/1_left_hip_pitch" in neurons and "/neurons/other/n10" in neurons
    times, vals = column(rrd["/neurons/motor/3_left_knee"], "Scalars:scalars")
    assert len(times) == ticks
    np.testing.assert_allclose(times, np.arange(ticks) * DT, atol=1e-9)
    np.testing.assert_array_equal(np.array(vals)[:, 0], traj.neurons[:, 2])
    # the motor neuron's output maps onto the knee's PD target (Table II range [-1.4, 0])
    _, target = column(rrd["/joints/left_knee/target"], "Scalars:scalars")
    np.testing.assert_allclose(np.array(target)[:, 0], -1.4 + 1.4 * traj.neurons[:, 2], rtol=0, atol=1e-12)
    # fitness so far ends on the episode's fitness
    _, fit = column(rrd["/fitness"], "Scalars:scalars")
    assert len(fit) == ticks and fit[-1][0] == moving["result"].fitness[0]


def test_static_geometry_matches_the_model(moving):
    rrd = moving["rrd"]
    geoms = {p for p in rrd if p.startswith("/world/") and rrd[p]["static"] and not rrd[p]["temporal"]}
    assert {"/world/ground/floor", "/world/bodies/pelvis/pelvis", "/world/bodies/left_shank/left_foot"} <= geoms
    cap = rrd["/world/bodies/left_thigh/left_thigh"]["static"][0]
    assert cap.column("Capsules3D:lengths").to_pylist()[0] == [pytest.approx(0.5)]
    assert cap.column("Capsules3D:radii").to_pylist()[0] == [pytest.approx(0.04)]
    foot = rrd["/world/bodies/left_shank/left_foot"]["static"][0]
    np.testing.assert_allclose(foot.column("Ellipsoids3D:half_sizes").to_pylist()[0][0], [0.08] * 3, rtol=1e-6)
    np.testing.assert_allclose(foot.column("Ellipsoids3D:centers").to_pylist()[0][0], [0, 0, -0.5], atol=1e-7)


def test_frames_match_episode_length_for_a_walker_that_stays_up(tmp_path):
    ep = EpisodeConfig(seconds=2.0).build()
    result, traj = write_recording(ep, standing_genome(ep.controller.layout), tmp_path / "stand.rrd")
    assert not result.fell[0]
    rrd = read_rrd(tmp_path / "stand.rrd")
    for body in ("pelvis", "left_thigh", "left_shank", "right_thigh", "right_shank"):
        assert len(column(rrd[f"/world/bodies/{body}"], "Transform3D:translation")[0]) == ep.n_ticks + 1 == 101
    assert len(column(rrd["/neurons/other/n7"], "Scalars:scalars")[0]) == ep.n_ticks
    path = rrd["/world/com_path"]["static"][-1].column("LineStrips3D:strips").to_pylist()[0][0]
    assert len(path) == 2.0 / 0.1 + 2  # one point per 0.1 s from t = 0, and the last one
    # both feet on the ground at the end: two contact points, at foot height
    _, pts = column(rrd["/world/contacts"], "Points3D:positions")
    assert len(pts[-1]) == 2
    np.testing.assert_allclose(np.array(pts[-1])[:, 2], 0.08, atol=0.01)


def test_capsule_endpoints_match_mujoco():
    """The geometry used for figures agrees with MuJoCo's own geom poses."""
    ep = EpisodeConfig(seconds=0.4).build()
    _, traj = record(ep, random_genome(ep.controller.layout, 4))
    m = ep.model
    d = mujoco.MjData(m)
    shape = next(s for s in geometry.shapes(m) if s.name == "right_shank")
    g = m.geom("right_shank").id
    for k in (0, len(traj.state_time) - 1):
        # put MuJoCo in the recorded pose by its body poses: compare with geom_xpos/xmat from the same bodies
        seg = geometry.segment(shape, traj.body_pos[k : k + 1, shape.body], traj.body_quat[k : k + 1, shape.body])[0]
        R = geometry.quat_to_mat(traj.body_quat[k, shape.body])
        centre = traj.body_pos[k, shape.body] + R @ m.geom_pos[g]
        np.testing.assert_allclose(seg.mean(axis=0), centre, atol=1e-12)
        assert np.linalg.norm(seg[1] - seg[0]) == pytest.approx(2 * m.geom_size[g, 1])
    mujoco.mj_forward(m, d)  # initial pose: segment of the model at rest
    seg0 = geometry.segment(shape, d.xpos[None, shape.body], d.xquat[None, shape.body])[0]
    axis = d.geom_xmat[g].reshape(3, 3)[:, 2]
    np.testing.assert_allclose(seg0, [d.geom_xpos[g] - 0.25 * axis, d.geom_xpos[g] + 0.25 * axis], atol=1e-12)


SAGITTAL = """
<mujoco model="sagittal">
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="hip" pos="0 0 1">
      <joint name="x" type="slide" axis="1 0 0"/>
      <joint name="z" type="slide" axis="0 0 1"/>
      <inertial pos="0 0 0" mass="48" diaginertia="1 1 1"/>
      <body name="thigh">
        <joint name="hip_r" type="hinge" axis="0 1 0"/>
        <geom name="thigh" type="capsule" fromto="0 0 0 0 0 -0.5" size="0.04" conaffinity="0"/>
        <body name="shank" pos="0 0 -0.5">
          <joint name="knee_r" type="hinge" axis="0 1 0"/>
          <geom name="shank" type="box" size="0.03 0.03 0.25" pos="0 0 -0.25" conaffinity="0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_any_model_draws_including_a_point_mass_without_geoms(tmp_path):
    from evobiped.record.recordings.rerun_recorder import log_geometry

    m = mujoco.MjModel.from_xml_string(SAGITTAL)
    kinds = {(s.name, s.kind, s.body) for s in geometry.shapes(m)}
    assert kinds == {("floor", "plane", 0), ("point_mass", "sphere", 1), ("thigh", "capsule", 2), ("shank", "box", 3)}
    rec = rr.RecordingStream("test", recording_id="geom")
    rec.save(tmp_path / "g.rrd")
    log_geometry(rec, m)
    rec.flush()
    rec.disconnect()
    rrd = read_rrd(tmp_path / "g.rrd")
    assert {"/world/ground/floor", "/world/bodies/hip/point_mass", "/world/bodies/thigh/thigh", "/world/bodies/shank/shank"} <= set(rrd)
    box = rrd["/world/bodies/shank/shank"]["static"][0]
    np.testing.assert_allclose(box.column("Boxes3D:half_sizes").to_pylist()[0][0], [0.03, 0.03, 0.25], rtol=1e-6)
    floor = rrd["/world/ground/floor"]["static"][0]
    np.testing.assert_allclose(floor.column("Boxes3D:half_sizes").to_pylist()[0][0], [5, 5, 0.005], rtol=1e-6)
    # the capsule starts at its lower cap centre and runs 0.5 m along its axis
    cap = rrd["/world/bodies/thigh/thigh"]["static"][0]
    start = np.array(cap.column("Capsules3D:translations").to_pylist()[0][0])
    q = np.array(cap.column("Capsules3D:quaternions").to_pylist()[0][0])[[3, 0, 1, 2]]
    end = start + geometry.quat_to_mat(q) @ [0, 0, 0.5]
    ends = sorted([start.tolist(), end.tolist()], key=lambda p: p[2])
    np.testing.assert_allclose(ends, [[0, 0, -0.5], [0, 0, 0]], atol=1e-6)


def test_evolution_log_has_one_row_per_generation(tmp_path):
    from evobiped.record.recordings.evolution_log import EvolutionLog

    best = [1.0, 2.5, 4.0]
    with EvolutionLog(path=tmp_path / "evo.rrd", recording_id="evo") as log:
        for g, b in enumerate(best):
            log.log_generation(g, best=b, mean=b / 2, worst=0.0, median=b / 3, evaluations=50, falls=40 - g)
    chunks = [c for c in rr.chunk.RrdReader(tmp_path / "evo.rrd").stream() if not c.is_static]
    rows = {}
    for c in chunks:
        rb = c.to_record_batch()
        gens = rb.column("generation").to_pylist()
        vals = [v[0] for v in rb.column("Scalars:scalars").to_pylist()]
        rows.setdefault(c.entity_path, {}).update(zip(gens, vals))
    assert rows["/evolution/best"] == {0: 1.0, 1: 2.5, 2: 4.0}
    assert rows["/evolution/mean"] == {0: 0.5, 1: 1.25, 2: 2.0}
    assert rows["/evolution/counts/falls"] == {0: 40.0, 1: 39.0, 2: 38.0}


def test_figures_are_written(tmp_path, monkeypatch):
    """Every replay figure is written as a PNG and draws what the episode did: the fitness graph the history, the
    motor figure one panel per motor output against time, the ground path the pelvis's planar track and where it
    ended, the stick figure the centre of mass's height, the motion sequence evenly spaced recorded states."""
    import matplotlib.image as mpimg

    from evobiped.record.png import figures

    drawn, save = {}, figures.save_figure

    def keep(fig, path, **kw):  # the figure as drawn, then written as the command writes it
        drawn[Path(path).name] = fig
        return save(fig, path, **kw)

    monkeypatch.setattr(figures, "save_figure", keep)
    ep = EpisodeConfig(seconds=1.0).build()
    _, traj = record(ep, random_genome(ep.controller.layout, 4))
    history = {"generation": np.arange(5.0), "best": np.array([1, 2, 2, 3, 4.0]), "mean": np.array([0.5, 1, 1.2, 1.5, 2.0])}
    paths = figures.replay_figures(traj, tmp_path / "figs", history=history)
    assert [p.name for p in paths] == ["fitness.png", "motor_neurons.png", "motion_sequence.png", "stick_figure.png", "ground_trajectory.png"]
    assert sorted(drawn) == sorted(p.name for p in paths)
    for p in paths:
        img = mpimg.imread(p)
        assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 300
        assert img[..., :3].std() > 0.05  # not a blank canvas

    best, mean = drawn["fitness.png"].axes[0].get_lines()[:2]
    assert np.array_equal(best.get_xdata(), history["generation"]) and np.array_equal(best.get_ydata(), history["best"])
    assert np.array_equal(mean.get_ydata(), history["mean"])
    panels, shown = drawn["motor_neurons.png"].axes, traj.command_time <= 10.0
    assert len(panels) == traj.n_motor > 1
    for i, ax in enumerate(panels):
        t, y = ax.get_lines()[0].get_data()
        assert np.array_equal(t, traj.command_time[shown]) and np.array_equal(y, traj.neurons[shown, i]), i
    ground = drawn["ground_trajectory.png"].axes[0].get_lines()
    assert np.array_equal(np.column_stack(ground[0].get_data()), traj.planar)
    end = [l for l in ground if l.get_marker() in ("s", "X")]
    assert len(end) == 1 and end[0].get_marker() == ("X" if traj.fell else "s")
    assert np.array_equal(np.ravel(end[0].get_data()), traj.planar[-1])
    heights = [l.get_ydata() for l in drawn["stick_figure.png"].axes[0].get_lines() if len(l.get_ydata()) > 2]
    assert any(np.array_equal(z, traj.com[: len(z), 2]) for z in heights)
    times = [float(ax.get_title().split()[2]) for ax in drawn["motion_sequence.png"].axes if ax.get_title().startswith("t = ")]
    assert len(times) > 1 and np.allclose(np.diff(times), times[1] - times[0], atol=0.011) and set(times) <= set(np.round(traj.state_time, 2))


def test_importing_the_package_does_not_import_rerun_or_matplotlib():
    import subprocess
    import sys

    code = "import sys, evobiped.cli, evobiped.usecases.replaying, evobiped.record.recordings.replay_recording, evobiped.usecases.evolving, evobiped.usecases.selecting, evobiped.record.png.figures, evobiped.record.recordings.rerun_recorder, evobiped.record.recordings.evolution_log; print(sorted({m.split('.')[0] for m in sys.modules} & {'rerun', 'matplotlib'}))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_the_targets_a_task_names_are_recorded(tmp_path, monkeypatch):
    """A task naming its presentations' targets (``Task.targets``, a steering walker's sources): all of
    them, and this walker's own (presentation 0 here) at every tick."""
    from evobiped.record.png.figures import ground_trajectory

    ep = EpisodeConfig(seconds=0.5).build()
    sources = np.array([[-3.0, -10.0], [3.0, -10.0]])
    monkeypatch.setattr(ep.task, "targets", lambda: sources)  # the task is shared by every episode of this config
    result, traj = write_recording(ep, random_genome(ep.controller.layout, 4), tmp_path / "s.rrd")
    np.testing.assert_array_equal(traj.sources, sources)
    assert traj.source.shape == (traj.n_ticks, 2) and (traj.source == sources[0]).all()
    rrd = read_rrd(tmp_path / "s.rrd")
    pts = rrd["/world/sources"]["static"][0].column("Points3D:positions").to_pylist()[0]
    np.testing.assert_array_equal(pts, [[-3, -10, 0], [3, -10, 0]])
    assert len(column(rrd["/world/source"], "Points3D:positions")[0]) == traj.n_ticks
    assert ground_trajectory(traj, tmp_path / "g.png").stat().st_size > 10_000


def test_recording_size_is_linear_in_episode_length(tmp_path):
    """Every entity holds a fixed number of values per row: twice the episode, twice the values."""
    cfg = EpisodeConfig(seconds=6.0, body_options={"fall_height": 0.01, "fall_tilt": 3.14159})  # no early end

    def values(x) -> int:
        return sum(values(v) for v in x) if isinstance(x, (list, tuple)) else 1

    counts = {}
    for seconds in (3.0, 6.0, 12.0):
        ep = dataclasses.replace(cfg, seconds=seconds).build()
        path = tmp_path / f"{seconds}.rrd"
        result, _ = write_recording(ep, random_genome(ep.controller.layout, 4), path)
        assert result.end_time[0] == seconds
        counts[seconds] = sum(values(rb.column(c).to_pylist()) for e in read_rrd(path).values() for rb in e["temporal"]
                              for c in rb.schema.names if c != "sim_time")
    growth = (counts[12.0] - counts[6.0]) / (counts[6.0] - counts[3.0])  # 2 when linear, 4 when quadratic
    assert growth == pytest.approx(2.0, abs=0.05), counts
