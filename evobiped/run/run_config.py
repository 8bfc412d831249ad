"""What defines an evolutionary run (:class:`RunConfig`, saved as config.json) and what it builds before any
file is written: the optimizer (any registered in :data:`evobiped.optimizers.OPTIMIZERS`), seeded from a genome file
when asked, within this machine's memory."""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass, field

import numpy as np

from ..files import rundir
from ..episode import EpisodeConfig
from ..core.errors import ConfigError, UserError
from ..core.options import check_fields, option, parse, refuse_unknown, scheduled
from ..physics.perturb import STRENGTHS
from ..evaluation import BACKENDS
from ..optimizers import OPTIMIZERS, Optimizer, described
from .curriculum import Curriculum, CurriculumOptions
from .stopping import RestartOptions, StopOptions


def _text(v) -> None:
    if not isinstance(v, str) or not v:
        raise ConfigError(f"must be a non-empty string, got {v!r}")


def _names(v) -> None:
    if not isinstance(v, (list, tuple)) or not all(isinstance(x, str) for x in v):
        raise ConfigError(f"must be a list of names, got {v!r}")


@dataclass(frozen=True, kw_only=True)
class RunConfig:
    """Everything that defines a run; saved as config.json."""

    episode: EpisodeConfig = field(default_factory=EpisodeConfig)
    optimizer: str = option("ga", described(), choices=OPTIMIZERS)  # the registry itself: one registered later counts
    #: optimizer name -> its settings (its ``Options``; given as a table or a parsed object), one for every registered
    #: optimizer (defaults where none are given): a config's ``[ga]``, ``[cma]``, ``[es]``, ``[map_elites]`` tables
    optimizer_options: dict = field(default_factory=dict)
    normalise: NormaliseOptions = field(default_factory=lambda: NormaliseOptions())
    curriculum: CurriculumOptions = field(default_factory=CurriculumOptions)
    stop: StopOptions = field(default_factory=StopOptions)
    restart: RestartOptions = field(default_factory=RestartOptions)
    generations: int = option(120, "generations to evolve", low=1, high=10**6, integer=True)
    budget: int | None = option(None, "episodes to evaluate: the run stops at the first generation boundary where the "
                                      "episodes it evaluated (genomes x presentations each, episodes_per_genome) reach "
                                      "this (none: every generation)", low=1, integer=True)
    seed: int = option(0, "run seed: every random draw of the run comes from it", low=0, integer=True)
    backend: str = option("process", "where episodes run", choices=tuple(BACKENDS))
    workers: int | None = option(None, "parallel workers (none: one per core)", low=1, integer=True)
    address: str | None = option(None, "an existing Ray cluster, HOST:PORT (backend ray)", check=_text)
    initial: str | None = option(None, "genome file or run directory whose best genome seeds the population (clones)",
                                 check=_text)
    frozen_blocks: tuple[str, ...] = option((), "gene blocks kept fixed (e.g. CPG weights when evolving only sensor "
                                                "weights)", check=_names)

    def __post_init__(self):
        given = self.optimizer_options
        unknown = [n for n in given if n not in OPTIMIZERS] if isinstance(given, dict) else [given]
        if unknown:
            raise ConfigError(
                f"optimizer_options: {unknown[0]!r} is no optimizer (choose from {', '.join(OPTIMIZERS)})")
        object.__setattr__(self, "optimizer_options", {name: parse(cls.Options, given.get(name, {}), cls.table)
                                                       for name, cls in OPTIMIZERS.items()})
        check_fields(self, "")
        # (parts built only when asked for)
        if self.normalise.running and not self.episode.parts()[1].normalises_inputs:
            raise ConfigError(f"normalise.running: controller {self.episode.controller!r} reads raw senses here "
                              "(it does not normalise its inputs)")
        OPTIMIZERS[self.optimizer].check_episode(self.options, self.episode)
        if self.curriculum.phases:
            Curriculum(self.curriculum).check(self.episode.parts()[2])
        if self.stop.active:
            self.stop.check(self.episode.parts()[2])
        self.restart.check(len(self.curriculum.phases), OPTIMIZERS[self.optimizer])
        if self.budget is not None and self.budget < (one := population_of(self) * episodes_per_genome(self)):
            raise ConfigError(f"budget: {self.budget} episodes is less than one generation's {one}")

    @property
    def options(self):
        """The run's optimizer's settings (its ``Options``)."""
        return self.optimizer_options[self.optimizer]

    def to_dict(self) -> dict:
        """config.json's table: the optimizers' settings as tables of their own (``ga``, ``cma``, ...), in the
        registry's order where ``optimizer_options`` stands."""
        d = {}
        for name, value in dataclasses.asdict(self).items():
            if name != "optimizer_options":
                d[name] = value
                continue
            for opt, cls in OPTIMIZERS.items():
                # the GA's and CMA-ES's always, the others' only in their own runs and when set: config.json as before
                if cls.always_written or (opt == self.optimizer and value[opt] != dataclasses.asdict(cls.Options())):
                    d[cls.table] = value[opt]
        d["episode"] = self.episode.to_dict()
        for name, cls in SECTIONS:
            if d[name] == dataclasses.asdict(cls()):  # written only when set: other runs' config.json as before
                del d[name]
        d["frozen_blocks"] = list(self.frozen_blocks)
        if d["budget"] is None:  # written only when set: other runs' config.json as before
            del d["budget"]
        return d

    @classmethod
    def from_dict(cls, d: dict, *, where: str = "config") -> "RunConfig":
        """The config a table of settings (a TOML file, config.json) gives; a bad setting is one ConfigError
        line, ``where: path.of.setting: what is wrong`` (``where``: the file or preset, if any)."""
        try:
            check_tables(d)
            keys = settings_keys()
            unknown = [k for k in d if k not in keys]
            if unknown:
                raise ConfigError(f"{unknown[0]}: unknown option (choose from {', '.join(keys)})")
            d = dict(d)
            episode = EpisodeConfig(**refuse_unknown(EpisodeConfig, d.pop("episode", {}), "episode"))
            optimizers = {name: parse(opt.Options, d.pop(opt.table, {}), opt.table) for name, opt in OPTIMIZERS.items()}
            extra = {name: parse(cls, d.pop(name, {}), name) for name, cls in SECTIONS}
            if isinstance(d.get("frozen_blocks"), list):
                d["frozen_blocks"] = tuple(d["frozen_blocks"])
            return cls(episode=episode, optimizer_options=optimizers, **extra, **d)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}" if where else str(exc)) from None


def _floors(v) -> None:
    if not (isinstance(v, dict) and all(isinstance(k, str) and isinstance(x, (int, float)) and not isinstance(x, bool)
                                        and x > 0
                                        for k, x in v.items())):
        raise ConfigError(f"must be a table of positive floors by sensor name, got {v!r}")


@dataclass(frozen=True, kw_only=True)
class NormaliseOptions:
    """The running observation normaliser (``[normalise]``; :mod:`evobiped.interface.normaliser`)."""

    running: bool = option(False, "normalise the controller's inputs by the running mean and std of the senses the "
                                  "run's walkers visited: ES's evaluation rows (theta); for the GA, CMA-ES and "
                                  "MAP-Elites every row evaluated (frozen into every genome file)")
    floor: float = option(0.2, "each input's std at least this fraction of its declared scale", above=0)
    floors: dict = option({"foot_contact": 0.5}, "absolute std floors by sensor name, in the sensor's units",
                          check=_floors)

    def __post_init__(self):
        check_fields(self, "normalise")


#: the run config's sections beside the episode and the optimizers, each written to config.json only when set
SECTIONS = (("normalise", NormaliseOptions), ("curriculum", CurriculumOptions), ("stop", StopOptions),
            ("restart", RestartOptions))


def _table_fields(cls: type) -> list[str]:
    """The settings of dataclass ``cls`` that are tables of settings (an options dataclass, or a dict): of a
    :class:`RunConfig`, each registered optimizer's table where ``optimizer_options`` stands."""
    out = []
    for f in dataclasses.fields(cls):
        if cls is RunConfig and f.name == "optimizer_options":
            out += [opt.table for opt in OPTIMIZERS.values()]
        elif f.default_factory is not dataclasses.MISSING:
            made = f.default_factory()
            if isinstance(made, dict) or dataclasses.is_dataclass(made):
                out.append(f.name)
    return out


def settings_keys() -> list[str]:
    """The keys of a run's settings table (a config file's, config.json's) in config.json's order: each registered
    optimizer's table where ``optimizer_options`` stands."""
    return [k for f in dataclasses.fields(RunConfig)
            for k in ([opt.table for opt in OPTIMIZERS.values()] if f.name == "optimizer_options" else [f.name])]


def check_tables(d, where: str = "") -> None:
    """ConfigError unless every setting that the declarations make a table (``episode``, ``ga``, ``cma``, the episode's
    option tables) is one in the settings ``d``, before flags are merged into them."""
    at = f"{where}: " if where else ""
    if not isinstance(d, dict):
        raise ConfigError(f"{at}the settings must be a table, got {type(d).__name__}")
    for cls, table, prefix in ((RunConfig, d, ""), (EpisodeConfig, d.get("episode"), "episode.")):
        if not isinstance(table, dict):
            continue
        for name in _table_fields(cls):
            if name in table and not isinstance(table[name], dict):
                raise ConfigError(f"{at}{prefix}{name}: must be a table of options, got {table[name]!r}")


#: memory a walker needs besides its genome: MuJoCo state, sensors, controller state (bytes, an upper estimate)
WALKER_BYTES = 256 * 1024


def check_memory(population: int, genes: int) -> None:
    """ConfigError unless a population of ``genes``-gene genomes and their simulations fit in half this machine's
    memory."""
    need = population * (genes * 8 * 8 + WALKER_BYTES)
    have = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    if need > have / 2:
        fits = int(have / 2 // (genes * 8 * 8 + WALKER_BYTES))
        raise ConfigError(f"population {population} needs about {need / 2**30:.3g} GiB for its genomes and "
                          f"simulations; this machine has {have / 2**30:.3g} GiB (at most {fits} walkers fit)")


def make_optimizer(config: RunConfig, start: np.ndarray | None = None) -> Optimizer:
    """Build the run's optimizer (the one registered under ``config.optimizer``) for the episode's genome layout, known
    from the declarations (nothing compiled); fails before any file is written.  ``start``: the start genome ``(G,)``
    when the run has one (:func:`start_genome`; None: read from ``config.initial``, as a new run does)."""
    layout = config.episode.layout()
    check_memory(population_of(config), layout.size)
    initial = None
    if config.initial:
        initial = layout.validate(start, what="start genome")[0] if start is not None else start_genome(config)
    mutable = None
    if config.frozen_blocks:
        slices = layout.slices()
        unknown = [b for b in config.frozen_blocks if b not in slices]
        if unknown:
            raise ConfigError(f"frozen_blocks {unknown} are not gene blocks of {config.episode.controller} (have "
                              f"{list(slices)})")
        mutable = np.ones(layout.size, bool)
        for b in config.frozen_blocks:
            mutable[slices[b]] = False
    cls = OPTIMIZERS[config.optimizer]
    options = cls.resolved(config.options, lambda: changing_context(config) is not None)
    return cls(layout, options, seed=config.seed, initial=initial, mutable=mutable)


def changing_context(config: RunConfig) -> str | None:
    """What scores one generation differently from another (None: nothing): the running normaliser, the curriculum,
    disturbances drawn per generation (or scheduled, or an aggregate that changes), a task's sources drawn per
    generation.  A fitness kept from an earlier generation (the GA's survivors) was scored under another context."""
    p = config.episode.perturbations
    strong = any(s.start > 0 or s.end > 0 for s in (scheduled(p, n) for n in STRENGTHS if n != "push_force"))
    friction = scheduled(p, "friction")
    task = config.episode.parts()[2]
    for what, changes in (("normalise.running", config.normalise.running),
                          ("curriculum", bool(config.curriculum.phases)),
                          ("episode.perturbations", p.pushes > 0 or strong or bool(friction.start) or bool(friction.end)
                           or p.assist > 0 or p.comparable_from > 0),
                          ("random sources", task.draw_sources((config.seed, 0)) is not None)):
        if changes:
            return what
    return None


def check_run(config: RunConfig) -> None:
    """What a new run refuses before any worker starts or file is written: a population beyond this machine's
    memory, a start genome that cannot be read or does not fit."""
    layout = config.episode.layout()
    check_memory(population_of(config), layout.size)
    if config.initial:
        start_genome(config)


def population_of(config: RunConfig) -> int:
    """Walkers evaluated per generation by the run's optimizer."""
    return OPTIMIZERS[config.optimizer].population_size(config.options, config.episode.layout().size)


def episodes_per_genome(config: RunConfig) -> int:
    """Episodes one genome's evaluation simulates: the task's presentations times the perturbed presentations."""
    p = config.episode.perturbations
    return int(config.episode.parts()[2].presentations) * (int(p.presentations) if p.active else 1)


def start_genome(config: RunConfig) -> np.ndarray | None:
    """The genome ``(G,)`` that ``config.initial`` names (None: the run has none).  Read once, when the run is
    created: the run directory keeps it (:data:`evobiped.files.rundir.START`), and a resume never reads the source
    again."""
    if not config.initial:
        return None
    return initial_genome(config.initial, config.episode, config.episode.layout())


def initial_genome(source: str, episode: EpisodeConfig, layout) -> np.ndarray:
    """The genome that seeds a run: a genome file or a run directory's best.json.

    A genome of a walking run seeds a run with extra input weights (steering):
    the missing trailing genes are filled with zeros (no influence).
    """
    found = rundir.resolve_genome(source)
    genome, cfg, path = found.genome, found.config, found.genome_path
    if cfg.body != episode.body or cfg.controller != episode.controller:
        raise UserError(f"{path} is a {cfg.body}/{cfg.controller} genome; this run needs "
                        f"{episode.body}/{episode.controller}")
    same = dataclasses.replace(cfg.controller_options,
                               inputs=None) == dataclasses.replace(episode.controller_options, inputs=None)
    if len(genome) < layout.size and same:
        genome = np.concatenate([genome, np.zeros(layout.size - len(genome))])
    return layout.validate(genome, what=f"genome in {path}")[0]
