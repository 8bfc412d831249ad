"""Every path builds its episode once: in a fresh process, each option table is parsed once, each body, controller
and task constructed once, and the MuJoCo model compiled once (an evolve with perturbations and its summary's nominal
re-run, a replay of another length with figures, the Gymnasium environments, the Taga experiments, a distillation's
rollouts beside its student alone)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from .conftest import ROOT, WALKERS

#: run in a fresh Python: counts every construction while ``SCENARIO`` runs, prints them as JSON
HARNESS = r'''
import collections, json, sys
import mujoco
import evobiped.cli, evobiped.episode.parts as parts, evobiped.core.options as options
from evobiped.bodies import BODIES
from evobiped.controllers import CONTROLLERS
from evobiped.tasks import TASKS

built = collections.Counter()

def counting(key, f):
    def wrapper(*a, **k):
        built[key] += 1
        return f(*a, **k)
    return wrapper

mujoco.MjModel.from_xml_path = counting("compile", mujoco.MjModel.from_xml_path)
mujoco.MjModel.from_xml_string = counting("compile", mujoco.MjModel.from_xml_string)
for registry in (BODIES, CONTROLLERS, TASKS):
    for cls in registry.values():
        def init(self, *a, __cls=cls, __init=cls.__init__, **k):
            if type(self) is __cls:  # not again for a registered parent's __init__
                built[__cls.__name__] += 1
            return __init(self, *a, **k)
        cls.__init__ = init
parse = options.parse
def counted_parse(cls, values, where, **kw):
    if not isinstance(values, cls):
        built["parse " + cls.__name__ + " " + json.dumps(values, sort_keys=True, default=repr)] += 1
    return parse(cls, values, where, **kw)
options.parse = parts.parse = counted_parse

SCENARIO
print("COUNTS " + json.dumps(built))
'''


def constructions(scenario: str, cwd: Path) -> dict[str, int]:
    """What a fresh process running ``scenario`` (Python, after the counters are in place) constructed."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    proc = subprocess.run([sys.executable, "-c", HARNESS.replace("SCENARIO", scenario)], capture_output=True, text=True,
                          cwd=cwd, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.split("COUNTS ", 1)[1])


def once_each(counts: dict[str, int], *expected: str) -> None:
    """Each of ``expected`` constructed exactly once; nothing constructed or parsed twice."""
    for name in expected:
        assert counts.get(name) == 1, (name, counts)
    assert max(counts.values()) == 1, counts


PERTURBED = {"presentations": 2, "pushes": 1, "push_force": 20.0, "target_noise": 0.01}


@pytest.fixture(scope="module")
def perturbed_run(tmp_path_factory):
    """A tiny evolve with perturbations (serial, 2 generations of 4, 0.3 s), and what its process constructed."""
    where = tmp_path_factory.mktemp("evolve")
    (where / "c.toml").write_text("[episode.perturbations]\n" + "".join(f"{k} = {v}\n" for k, v in PERTURBED.items()))
    counts = constructions('evobiped.cli.main(["evolve", "--config", "c.toml", "--generations", "2", "--population", '
                           '"4", "--seconds", "0.3", "--backend", "serial", "--out", "run", "--quiet"])', where)
    return where / "run", counts


def test_an_evolve_with_perturbations_parses_builds_and_compiles_once(perturbed_run):
    """The run's config, the defaults its settings are checked against, its best genome file and the summary's
    nominal re-run of the best: one body, controller, task and model, each table parsed once."""
    run, counts = perturbed_run
    assert (run / "summary.json").is_file()
    table = "parse PerturbationOptions " + json.dumps(PERTURBED, sort_keys=True)
    once_each(counts, "compile", "ReilBiped", "CTRNN", "WalkTask", table)


def test_a_replay_of_another_length_with_figures_builds_once(perturbed_run):
    run, _ = perturbed_run
    counts = constructions(f'evobiped.cli.main(["replay", {str(run)!r}, "--seconds", "0.2", "--figures", "figs", '
                           '"--out", "r.rrd", "--quiet"])', run.parent)
    assert (run.parent / "figs").is_dir()
    once_each(counts, "compile", "ReilBiped", "CTRNN", "WalkTask")


def test_the_gymnasium_environments_build_through_the_episode_config():
    """A single and a vector environment of the same options share their parts (no controller is built)."""
    counts = constructions('''
import gymnasium, numpy as np, evobiped.envs
env = gymnasium.make("evobiped/ReilBiped-v0", seconds=0.1, task_options={"fitness": "distance"})
env.reset(seed=0); env.step(np.zeros(6, np.float32))
venv = evobiped.envs.ReilBipedVectorEnv(3, seconds=0.1, task_options={"fitness": "distance"})
venv.reset(seed=0); venv.step(np.zeros((3, 6)))
''', Path.cwd())
    once_each(counts, "compile", "ReilBiped", "WalkTask", 'parse WalkOptions {"fitness": "distance"}')
    assert not any(c in counts for c in ("CTRNN", "Matsuoka", "Simbicon"))


def test_the_taga_experiments_build_their_walker_once():
    """Two experiments of the same walker: one body (whose ground one of them changes), controller, task, model."""
    counts = constructions('''
from evobiped.experiments.taga import protocols
protocols.ground_switch([8000.0], [800.0], before=0.1, after=0.1, window=0.1)
protocols.steady(5.5, seconds=0.2, window=0.1)
''', Path.cwd())
    once_each(counts, "compile", "TagaBiped", "Matsuoka", "WalkTask")


def test_a_distillation_s_rollouts_and_student_share_the_teacher_s_body():
    counts = constructions(f'''
from evobiped.distill import DistillOptions, collect, student_config
from evobiped.files.genome_file import load_genome
g, teacher, _ = load_genome({str(WALKERS / "simbicon_cma_seed3.json")!r})
student = student_config(teacher.nominal(), {{"n_neurons": 8}}, seconds=0.2)
collect(teacher, g, student, student.layout().init_mean, beta=0.5, options=DistillOptions(rollouts=2, seconds=0.2),
        key=(0, 0))
student.build().run(student.layout().init_mean)
''', Path.cwd())
    once_each(counts, "compile", "ReilBiped", "Simbicon", "CTRNN", "WalkTask")


def test_configs_of_the_same_tables_share_their_parts_and_write_back_what_they_were_given():
    """The parts are kept by the tables as given: another length shares them, other settings do not, and 100 and
    100.0 stay apart (a config writes back the type it read); each episode has its own copy of the body's model."""
    import dataclasses

    from evobiped.episode import EpisodeConfig

    a = EpisodeConfig(seconds=1.0, body_options={"kp": 100})
    same = EpisodeConfig(seconds=1.0, body_options={"kp": 100})
    longer = dataclasses.replace(a, seconds=3.0)
    assert all(x is y for x, y in zip(a.parts(), same.parts())) and all(x is y for x,
                                                                        y in zip(a.parts(), longer.parts()))
    as_float = EpisodeConfig(seconds=1.0, body_options={"kp": 100.0})
    assert as_float.body_options is not a.body_options and as_float.parts()[0] is not a.parts()[0]
    assert type(a.to_dict()["body_options"]["kp"]) is int and type(as_float.to_dict()["body_options"]["kp"]) is float
    assert EpisodeConfig(body_options={"kp": 120.0}).parts()[0].kp != a.parts()[0].kp
    changed = a.build()
    changed.model.opt.gravity[:] = 0.0  # an episode's model is its own: another episode of the body keeps its gravity
    assert longer.build().model.opt.gravity[2] == -9.81 and a.parts()[0].build_model().opt.gravity[2] == -9.81


def test_an_episode_without_a_controller_needs_its_period_and_takes_no_controller_settings():
    from evobiped.episode import EpisodeConfig
    from evobiped.core.errors import ConfigError

    with pytest.raises(ConfigError, match="needs its control period"):
        EpisodeConfig(controller=None)
    with pytest.raises(ConfigError, match="^episode.control_dt: only an episode without a controller takes one"):
        EpisodeConfig(control_dt=0.02)
    with pytest.raises(ConfigError, match="^episode.controller_options: an episode without a controller takes none"):
        EpisodeConfig(controller=None, control_dt=0.02, controller_options={"latency": 1})
    outside = EpisodeConfig(controller=None, control_dt=0.02)
    with pytest.raises(ConfigError, match="no genome"):
        outside.layout()
    assert outside.build().control_dt == 0.02 and outside.parts()[1] is None
    assert "control_dt" not in EpisodeConfig().to_dict() and outside.to_dict()["control_dt"] == 0.02
