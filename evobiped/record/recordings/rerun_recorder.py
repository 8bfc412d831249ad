"""A recorded episode as a Rerun recording, with a blueprint that opens on a sensible layout.

Entity tree (time series on the ``sim_time`` timeline, in s)::

    world/ground/<geom>            static: the floor (and any other world geom)
    world/bodies/<body>            Transform3D per state row (pose after each tick, and t = 0)
    world/bodies/<body>/<geom>     static: capsule / sphere / ellipsoid / cylinder / box in the body frame
    world/bodies/<body>/sites      static: visible sites (ears, ...)
    world/com                      Points3D: the centre of mass
    world/com_path                 static LineStrips3D: the centre-of-mass path of the whole episode (one point per 0.1
    s) world/contacts                 Points3D: touch sensors that touch the ground
    world/source, world/sources    Points3D: sound sources (when the task has them)
    world/presentations/<j>/path   static LineStrips3D: the centre-of-mass path towards source j (several sources)
    presentations/<j>/sound        Scalars: the ear signal s heard on the way to source j
    neurons/motor/<i>_<actuator>   Scalars: motor neuron outputs (thick lines)
    neurons/other/n<i>             Scalars: the other neurons
    joints/<actuator>/angle        Scalars: joint angle (rad)
    joints/<actuator>/target       Scalars: PD target (rad) or torque (N m)
    contacts/<touch sensor>        Scalars: 1 while touching
    sensors/<name>                 Scalars: every body and task sensor (e.g. the ear signal)
    commands/speed, commands/turning  Scalars: a commanded walker's commanded and walked speed (m/s) and turning rate
                                   (deg/s), walked as 1 s running means
    fitness                        Scalars: fitness so far

Whole trajectories go in with ``send_columns`` (one call per entity); every
entity holds a fixed amount per row, so a recording grows linearly with the
episode length.
"""

from __future__ import annotations

import numpy as np

from ..geometry import PLANE_HALF_SIZE, body_names, quat_to_mat, shapes, wxyz_to_xyzw
from ..trajectory import Trajectory, TrajectoryRecorder

TIMELINE = "sim_time"
#: the centre-of-mass path keeps one point per this many seconds (plus the last one)
TRAIL_DT = 0.1
_MOTOR_COLORS = [(228, 26, 28), (55, 126, 184), (77, 175, 74), (152, 78, 163), (255, 127, 0), (166, 86, 40),
                 (247, 129, 191), (0, 150, 150)]


def _rgb(rgba) -> list[int]:
    return [int(round(255 * float(c))) for c in rgba]


def log_geometry(rec, model) -> None:
    """Static shapes of every geom: world geoms under ``world/ground``, the rest under their body."""
    import rerun as rr

    names = body_names(model)
    for s in shapes(model):
        root = "world/ground" if s.body == 0 else f"world/bodies/{names[s.body]}"
        path = f"{root}/{s.name}"
        q = [rr.Quaternion(xyzw=wxyz_to_xyzw(s.quat))]
        col = [_rgb(s.rgba)]
        if s.kind == "capsule":
            # MuJoCo: centred, along the geom z axis; Rerun: from the origin along +z
            start = s.pos - quat_to_mat(s.quat) @ np.array([0.0, 0.0, s.size[1]])
            arch = rr.Capsules3D(lengths=[2 * s.size[1]], radii=[s.size[0]], translations=[start], quaternions=q,
                                 colors=col)
        elif s.kind == "sphere":
            arch = rr.Ellipsoids3D(half_sizes=[[s.size[0]] * 3], centers=[s.pos], colors=col, fill_mode="solid")
        elif s.kind == "ellipsoid":
            arch = rr.Ellipsoids3D(half_sizes=[s.size], centers=[s.pos], quaternions=q, colors=col, fill_mode="solid")
        elif s.kind == "cylinder":
            arch = rr.Cylinders3D(lengths=[2 * s.size[1]], radii=[s.size[0]], centers=[s.pos], quaternions=q,
                                  colors=col)
        elif s.kind == "box":
            arch = rr.Boxes3D(half_sizes=[s.size], centers=[s.pos], quaternions=q, colors=col, fill_mode="solid")
        elif s.kind == "plane":
            hx, hy = (s.size[i] if s.size[i] > 0 else PLANE_HALF_SIZE for i in (0, 1))
            # a thin slab whose top face is the plane
            centre = s.pos + np.array([0.0, 0.0, -0.005])
            arch = rr.Boxes3D(half_sizes=[[hx, hy, 0.005]], centers=[centre], quaternions=q, colors=col,
                              fill_mode="solid")
        else:  # heightfields and meshes: mark where they are
            arch = rr.Points3D([s.pos], labels=[f"{s.kind} {s.name} (not drawn)"], colors=col)
        rec.log(path, arch, static=True)
    sites = [i for i in range(model.nsite) if model.site_rgba[i, 3] > 0 and model.site_bodyid[i] > 0]
    for b in sorted({int(model.site_bodyid[i]) for i in sites}):
        mine = [i for i in sites if model.site_bodyid[i] == b]
        rec.log(
            f"world/bodies/{names[b]}/sites",
            rr.Points3D(
                [model.site_pos[i] for i in mine],
                radii=[0.02] * len(mine),
                labels=[model.site(i).name for i in mine],
                colors=[[255, 200, 0]] * len(mine),
            ),
            static=True,
        )


def _cols(times) -> list:
    """The ``sim_time`` index of a ``send_columns`` call for these times (s)."""
    import rerun as rr

    return [rr.TimeColumn(TIMELINE, duration=np.asarray(times, float))]


def _log_commands(rec, traj: Trajectory) -> None:
    """A commanded walker's commands (its ``command_speed`` and ``command_turning`` senses, as told) beside what it
    walked: the pelvis's path along its facing and its facing's turn per tick, each a 1 s running mean."""
    import rerun as rr

    tk = _cols(traj.tick_time)
    R = quat_to_mat(traj.body_quat[:, 1])  # the root body (the pelvis): its x axis on the ground is the facing
    facing = np.arctan2(R[:, 1, 0], R[:, 0, 0])
    dt = np.diff(traj.state_time)
    step = np.diff(traj.planar, axis=0)
    along = np.einsum("ki,ki->k", step, np.stack([np.cos(facing[1:]), np.sin(facing[1:])], axis=1)) / dt
    turn = np.degrees(np.diff(np.unwrap(facing)) / dt)
    k = max(1, int(round(1.0 / traj.dt)))
    mean = lambda x: np.convolve(x, np.ones(k) / k, mode="full")[: len(x)] * k / np.minimum(np.arange(1, len(x) + 1), k)
    told = {"speed": traj.sensors["command_speed"][:, 0], "turning": np.degrees(traj.sensors["command_turning"][:, 0])}
    for name, walked, unit in (("speed", along, "m/s"), ("turning", turn, "deg/s")):
        rec.log(f"commands/{name}", rr.SeriesLines(names=[f"commanded ({unit})", f"walked, 1 s mean ({unit})"],
                                                   colors=[[0, 0, 0], [220, 60, 30]], widths=[2.0, 1.5]), static=True)
        rec.send_columns(f"commands/{name}", indexes=tk,
                         columns=rr.Scalars.columns(scalars=np.column_stack([told[name], mean(walked)])))


def log_trajectory(rec, traj: Trajectory) -> None:
    """Every time series of ``traj`` on the ``sim_time`` timeline (geometry: :func:`log_geometry`)."""
    import rerun as rr

    names = body_names(traj.model)
    st = _cols(traj.state_time)
    for b in range(1, traj.model.nbody):
        rec.send_columns(
            f"world/bodies/{names[b]}",
            indexes=st,
            columns=rr.Transform3D.columns(translation=traj.body_pos[:, b],
                                           quaternion=wxyz_to_xyzw(traj.body_quat[:, b])),
        )
    rec.log("world/com", rr.Points3D.from_fields(radii=[0.03], colors=[[20, 20, 20]], labels=["centre of mass"]),
            static=True)
    rec.send_columns("world/com", indexes=st, columns=rr.Points3D.columns(positions=traj.com))
    rec.log("world/com_path", rr.LineStrips3D([_path(traj.state_time, traj.com)], radii=[0.008], colors=[[30, 30, 30]],
                                              labels=["centre-of-mass path"]), static=True)

    tk = _cols(traj.tick_time)
    if traj.touch_names:
        touching = traj.touch > 0
        counts = touching.sum(axis=1)
        rec.log("world/contacts", rr.Points3D.from_fields(radii=[0.04], colors=[[230, 40, 40]]), static=True)
        rec.send_columns(
            "world/contacts",
            indexes=tk,
            columns=rr.Points3D.columns(positions=traj.touch_pos[touching].reshape(-1, 3)).partition(counts),
        )
        for k, name in enumerate(traj.touch_names):
            rec.log(f"contacts/{name}", rr.SeriesLines(names=[name]), static=True)
            rec.send_columns(f"contacts/{name}", indexes=tk,
                             columns=rr.Scalars.columns(scalars=touching[:, k].astype(float)))
    rec.log("fitness", rr.SeriesLines(names=["fitness so far"], colors=[[0, 0, 0]], widths=[2.0]), static=True)
    rec.send_columns("fitness", indexes=tk, columns=rr.Scalars.columns(scalars=traj.fitness))
    for name, vals in traj.sensors.items():
        k = vals.shape[1]
        rec.log(f"sensors/{name}", rr.SeriesLines(names=[f"{name}[{i}]" for i in range(k)] if k > 1 else [name]),
                static=True)
        rec.send_columns(f"sensors/{name}", indexes=tk, columns=rr.Scalars.columns(scalars=vals))
    if "command_speed" in traj.sensors:
        _log_commands(rec, traj)
    if traj.source is not None:
        src = np.column_stack([traj.source, np.zeros(len(traj.source))])
        rec.log("world/source", rr.Points3D.from_fields(radii=[0.12], colors=[[255, 140, 0]], labels=["sound source"]),
                static=True)
        rec.send_columns("world/source", indexes=tk, columns=rr.Points3D.columns(positions=src))
    if traj.sources is not None:
        s = np.asarray(traj.sources, float)
        rec.log(
            "world/sources",
            rr.Points3D(np.column_stack([s, np.zeros(len(s))]), radii=0.08, colors=[255, 200, 120],
                        labels=[f"source {i + 1}" for i in range(len(s))]),
            static=True,
        )

    cm = _cols(traj.command_time)
    for i in range(traj.neurons.shape[1]):
        if i < traj.n_motor:
            act = traj.actuator_names[i] if i < len(traj.actuator_names) else f"out{i}"
            path, label, width = f"neurons/motor/{i + 1}_{act}", f"M{i + 1} {act}", 2.5
            color = _MOTOR_COLORS[i % len(_MOTOR_COLORS)]
        else:
            path, label, width, color = f"neurons/other/n{i + 1}", f"n{i + 1}", 1.0, (140, 140, 140)
        rec.log(path, rr.SeriesLines(names=[label], widths=[width], colors=[color]), static=True)
        rec.send_columns(path, indexes=cm, columns=rr.Scalars.columns(scalars=traj.neurons[:, i]))
    what = "PD target (rad)" if traj.action_kind == "position" else "torque (N m)"
    for a, act in enumerate(traj.actuator_names):
        if not np.isnan(traj.joint_angle[:, a]).all():
            rec.log(f"joints/{act}/angle", rr.SeriesLines(names=[f"{act} angle (rad)"], widths=[2.0]), static=True)
            rec.send_columns(f"joints/{act}/angle", indexes=st,
                             columns=rr.Scalars.columns(scalars=traj.joint_angle[:, a]))
        rec.log(f"joints/{act}/target", rr.SeriesLines(names=[f"{act} {what}"]), static=True)
        rec.send_columns(f"joints/{act}/target", indexes=cm, columns=rr.Scalars.columns(scalars=traj.action[:, a]))


def log_presentations(rec, trajs: list[Trajectory]) -> None:
    """Every presentation of a task with several (one per sound source): its path on the ground, its
    source, and the ear signal heard on the way (``presentations/<j>/sound``), j counted from 1."""
    import rerun as rr

    for j, traj in enumerate(trajs, 1):
        color = _MOTOR_COLORS[(j - 1) % len(_MOTOR_COLORS)]
        rec.log(f"world/presentations/{j}/path",
                rr.LineStrips3D([_path(traj.state_time, traj.com)], radii=[0.01], colors=[color],
                                                                  labels=[f"towards source {j}"]), static=True)
        if traj.source is not None:
            rec.log(f"world/presentations/{j}/source",
                    rr.Points3D([[*traj.source[0], 0.0]], radii=[0.12], colors=[color],
                                                                    labels=[f"source {j}"]), static=True)
        if "sound" in traj.sensors:
            rec.log(f"presentations/{j}/sound", rr.SeriesLines(names=[f"ear signal s, source {j}"], colors=[color]),
                    static=True)
            rec.send_columns(f"presentations/{j}/sound", indexes=_cols(traj.tick_time),
                             columns=rr.Scalars.columns(scalars=traj.sensors["sound"][:, 0]))


def _path(times: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The whole path ``(n, 3)`` -> one point per ``TRAIL_DT`` s and the last one."""
    step = max(1, int(round(TRAIL_DT / max(times[1] - times[0], 1e-9)))) if len(times) > 1 else 1
    return np.concatenate([points[::step], points[-1:]])


def blueprint(traj: Trajectory, *, with_evolution: bool = False, with_presentations: bool = False,
              with_video: bool = False):
    """3D view (tracking the first moving body) beside time-series panels; ``with_video``: the rendered
    frames (entity ``video``) in a tab beside the 3D view."""
    import rerun.blueprint as rrb

    names = body_names(traj.model)
    plots = [
        rrb.TimeSeriesView(origin="neurons/motor", name="motor neurons"),
        rrb.TimeSeriesView(origin="neurons/other", name="other neurons"),
        rrb.Tabs(*[rrb.TimeSeriesView(origin=f"joints/{a}", name=a) for a in traj.actuator_names], name="joints"),
        rrb.Tabs(
            rrb.TimeSeriesView(origin="contacts", name="foot contacts"),
            rrb.TimeSeriesView(origin="sensors", name="sensors"),
            *([rrb.TimeSeriesView(origin="presentations", name="ear signal per source")] if with_presentations else []),
            *([rrb.TimeSeriesView(origin="evolution", name="evolution (per generation)")] if with_evolution else []),
        ),
    ]
    view3d = rrb.Spatial3DView(
        origin="world",
        name="walker",
        eye_controls=rrb.EyeControls3D(tracking_entity=f"world/bodies/{names[1]}") if traj.model.nbody > 1 else None,
    )
    if with_video:
        view3d = rrb.Tabs(view3d, rrb.Spatial2DView(origin="video", name="video"))
    left = rrb.Vertical(view3d, rrb.TimeSeriesView(origin="fitness", name="fitness so far"), row_shares=[3, 1])
    return rrb.Blueprint(rrb.Horizontal(left, rrb.Vertical(*plots), column_shares=[3, 2]), collapse_panels=True)


def log_episode(rec, traj: Trajectory) -> None:
    """Geometry and time series of ``traj`` into an open recording stream."""
    log_geometry(rec, traj.model)
    log_trajectory(rec, traj)


class RerunRecorder(TrajectoryRecorder):
    """Episode listener that writes the episode to ``rec`` (a ``rr.RecordingStream``) when it ends."""

    def __init__(self, rec, index: int = 0):
        super().__init__(index)
        self.rec = rec

    def end(self, result) -> None:
        super().end(result)
        log_episode(self.rec, self.trajectory)
