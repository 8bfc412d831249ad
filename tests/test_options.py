"""Typed options: the declarations, their one-line errors with the setting's path, and the option tables of
docs/usage.md."""

import dataclasses

import pytest

from evobiped.bodies import BODIES
from evobiped.controllers import CONTROLLERS
from evobiped.episode import EpisodeConfig
from evobiped.core.errors import ConfigError
from evobiped.run.run_config import RunConfig
from evobiped.core.options import markdown_table, option, parse
from evobiped import readme
from evobiped.readme import USAGE, render, sections, tables
from evobiped.tasks import TASKS


def test_the_usage_pages_tables_are_the_declarations():
    """docs/usage.md's option tables; regenerate with ``python -m evobiped.readme``."""
    text = USAGE.read_text()
    assert sections(text) == list(readme.FIXED)  # the tables outside the registries have their markers
    for kind, (reg, part, _) in readme.REGISTRIES.items():  # every registered component its section, in order
        headings = [line for line in readme.generated()[part].splitlines() if line.startswith("### ")]
        assert [line.split("`")[1] for line in headings] == list(reg)
    assert render(text) == text


def test_a_table_changes_with_its_declaration():
    @dataclasses.dataclass(frozen=True, kw_only=True)
    class Knobs:
        gain: float = option(2.0, "loop gain", unit="N m/rad", above=0)
        mode: str = option("a", "which mode", choices=("a", "b"))

    table = markdown_table(Knobs)
    assert "| `gain` | `2` | N m/rad | > 0 | loop gain |" in table
    assert "| `mode` | `\"a\"` |  | `a`, `b` | which mode |" in table
    text = "x\n<!-- options: body reil -->\nstale\n<!-- end options -->\ny\n"
    assert render(text) == f"x\n<!-- options: body reil -->\n{tables()['body reil']}<!-- end options -->\ny\n"


def test_every_component_declares_defaults_that_pass_its_own_checks():
    for reg, where in ((BODIES, "b"), (CONTROLLERS, "c"), (TASKS, "t")):
        for name, cls in reg.items():
            opts = parse(cls.Options, {}, where)
            for f in dataclasses.fields(opts):
                assert f.metadata["doc"], (name, f.name)  # every option says what it is


BAD = [
    (dict(body_options={"kp": -5}), "episode.body_options.kp: must be > 0 N m/rad, got -5"),
    (dict(body_options={"kp": "stiff"}), "episode.body_options.kp: must be a number, got 'stiff'"),
    (dict(body="taga", body_options={"slope": 0.6}), "episode.body_options.slope: must be in [-0.5, 0.5], got 0.6"),
    (dict(body="taga", body_options={"kg": [1.0, -1.0]}), "episode.body_options.kg: must be a number > 0 (or a list"),
    (dict(controller_options={"n_neurons": 0}), "episode.controller_options.n_neurons: must be in [1, 1000], got 0"),
    (dict(controller_options={"time_constants": [0.005, 1.0]}), "episode.controller_options: time_constants must be "
                                                                "[low, high]"),
    (dict(controller="matsuoka", controller_options={"feedback": "yes"}),
     "episode.controller_options.feedback: must be one of auto, taga, senses, none, got 'yes'"),
    (dict(controller="g3", controller_options={"go": [[1.0, 0.1], [0.5, 0.2]]}),
     "episode.controller_options.go: a schedule's times must increase"),
    (dict(controller="simbicon", controller_options={"dtt": 0.01}), "episode.controller_options.dtt: unknown option "
                                                                    "(choose from dt, sound_limit, inputs, genes, "
                                                                    "latency, frame, input_norm)"),
    (dict(task_options={"fitness": "forward", "cyclic_weight": 1.0}), "episode.task_options: the cyclic criterion "
                                                                      "multiplies eq. 4"),
    (dict(task="steer", task_options={"sources": [[0.1, 0.0]]}), "episode.task_options.sources: the source (0.1, 0) is "
                                                                 "at the walker's start"),
]


@pytest.mark.parametrize("episode, words", BAD, ids=[w.split(":")[0] for _, w in BAD])
def test_a_bad_option_is_refused_when_the_config_is_loaded_naming_its_path(episode, words):
    with pytest.raises(ConfigError) as exc:
        RunConfig.from_dict({"episode": episode}, where="c.toml")
    assert str(exc.value).startswith("c.toml: ") and words in str(exc.value)
    with pytest.raises(ConfigError, match="^" + words.replace("[", r"\[").replace("(", r"\(").replace(")", r"\)")):
        EpisodeConfig(**episode)


@pytest.mark.parametrize("table, words", [({"ga": {"fittest_fraction": 1.0}},
                                           "ga.fittest_fraction: must be < 1, got 1.0"),
                                          ({"cma": {"sigma0": 0}}, "cma.sigma0: must be > 0, got 0"),
                                          ({"cma": {"population": 1}},
                                           "cma.population: must be a whole number in [2, 1e+07]"),
                                          ({"generations": 0}, "generations: must be in [1, 1e+06], got 0"),
                                          ({"workers": 0}, "workers: must be >= 1, got 0"),
                                          ({"optimizer": "de"}, "optimizer: must be one of ga, cma, es, map-elites, "
                                                                "got 'de'")])
def test_bad_run_settings_name_their_path(table, words):
    with pytest.raises(ConfigError, match="^c.toml: " + words.replace("[", r"\[").replace("+", r"\+")):
        RunConfig.from_dict(table, where="c.toml")


def test_a_config_parses_each_table_once_and_writes_back_what_it_was_given(monkeypatch):
    """EpisodeConfig parses its tables into frozen Options when it is made; building the episode (body,
    controller, task, perturbations) parses nothing again, and to_dict gives back the tables as given."""
    import evobiped.core.options as options
    from evobiped.bodies.reil import ReilOptions
    from evobiped.controllers.ctrnn import CTRNNOptions

    tables = dict(body_options={"kp": 60.0}, controller_options={"n_neurons": 8, "latency": 2},
                  task_options={"fitness": "distance"}, perturbations={"pushes": 1})
    cfg = EpisodeConfig(seconds=1.0, **tables)
    assert isinstance(cfg.body_options, ReilOptions) and cfg.body_options.kp == 60.0 and cfg.body_options.kv == 2.0
    assert isinstance(cfg.controller_options, CTRNNOptions) and cfg.controller_options.latency == 2 == cfg.latency
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.body_options.kp = 1.0
    parses = []
    monkeypatch.setattr(options, "refuse_unknown", lambda *a, **k: parses.append(a) or a[1])
    episode = dataclasses.replace(cfg, seconds=0.5).build()
    assert parses == [] and episode.latency == 2 and episode.perturbations.pushes == 1
    assert episode.body.options is cfg.body_options and episode.controller.options is cfg.controller_options
    monkeypatch.undo()
    d = cfg.to_dict()
    assert {k: d[k] for k in tables} == tables
    assert EpisodeConfig(**d) == cfg and EpisodeConfig(**d).to_dict() == d
