"""The generated parts of the documentation: docs/usage.md's option tables, presets table and progress lines,
docs/gym.md's environments and observation parts, all derived from the registries and the declarations.

Every registered body, controller, task and optimizer has its section in docs/usage.md, generated whole (heading,
its ``docs_note``, its option table) between ``<!-- generated: bodies -->`` (``controllers``, ``tasks``,
``optimizers``) and ``<!-- end generated -->``; every body that declares an environment its row of docs/gym.md's
``environments`` and its observation table in ``observations`` (each part described by the body's or the task's
``sensor_text``).  The other option tables sit between ``<!-- options: ID -->`` and ``<!-- end options -->``, ID
naming them (``episode perturbations``, ``run stop``, ``environment``, ...); any other generated part between
``<!-- generated: ID -->`` and ``<!-- end generated -->`` (``presets``, ``progress``).  ``python -m evobiped.readme``
rewrites them; tests/test_options.py and tests/test_docs.py check that they agree with the code.
"""

from __future__ import annotations

import re
from pathlib import Path

from .bodies import BODIES
from .controllers import CONTROLLERS
from .controllers.base import GENERIC_CONTROLLER_OPTIONS
from .envs.walkers import EnvOptions, env_id, observation
from .run.curriculum import CurriculumOptions
from .run.stopping import RestartOptions, StopOptions
from .run.run_config import NormaliseOptions
from .core.options import markdown_table
from .optimizers import OPTIMIZERS
from .physics.perturb import PerturbationOptions
from .tasks import TASKS
from .tasks import terms

DOCS = Path(__file__).resolve().parent.parent / "docs"
#: the page that holds the option tables
USAGE = DOCS / "usage.md"
#: the Gymnasium page
GYM = DOCS / "gym.md"
#: a generated option table: its id, the table
MARKER = re.compile(r"(<!-- options: (?P<id>[a-z0-9_ -]+) -->\n)(?P<table>.*?)(<!-- end options -->)", re.S)
#: any other generated part: its id, the text
GENERATED = re.compile(r"(<!-- generated: (?P<id>[a-z0-9_ -]+) -->\n)(?P<table>.*?)(<!-- end generated -->)", re.S)

#: the registries whose every entry has a generated section: kind -> (the registry, the part of docs/usage.md that
#: holds their sections, the config table of their options (None: each optimizer's own ``table``))
REGISTRIES = {"body": (BODIES, "bodies", "episode.body_options"),
              "controller": (CONTROLLERS, "controllers", "episode.controller_options"),
              "task": (TASKS, "tasks", "episode.task_options"), "optimizer": (OPTIMIZERS, "optimizers", None)}
#: the option tables outside the registries, by section id
FIXED = {"episode perturbations": PerturbationOptions, "run normalise": NormaliseOptions,
         "run curriculum": CurriculumOptions, "run stop": StopOptions, "run restart": RestartOptions,
         "environment": EnvOptions}


def tables() -> dict[str, str]:
    """Every option table, by section id: each registered component's (``body reil``, ``optimizer ga``, ...), then
    those of :data:`FIXED`."""
    out = {}
    for kind, (reg, _, _) in REGISTRIES.items():
        for name, cls in reg.items():
            # every controller's generic options (inputs, genes, latency) are described once, beside the tables
            out[f"{kind} {name}"] = markdown_table(cls.Options, skip=GENERIC_CONTROLLER_OPTIONS if kind == "controller"
                                                   else ())
    return out | {name: markdown_table(options) for name, options in FIXED.items()}


def component_sections(kind: str) -> str:
    """The sections of every registered component of ``kind`` (``"body"``, ...): a heading naming its config table
    (the first's; each optimizer's), its ``docs_note``, its option table."""
    reg, _, table = REGISTRIES[kind]
    found, out = tables(), []
    for i, (name, cls) in enumerate(reg.items()):
        where = f"`[{cls.table if table is None else table}]`"
        out.append(f"### {kind.title()} `{name}`{f' ({where})' if table is None or i == 0 else ''}\n\n"
                   + (f"{cls.docs_note}\n\n" if cls.docs_note else "") + found[f"{kind} {name}"])
    return "\n".join(out)


def observation_table(body: str) -> str:
    """The observation of ``body``'s environment part by part: indices, part, width, what it reads (the body's and
    the walk task's ``sensor_text``; KeyError for a part neither describes)."""
    rows, at = ["| indices | part | width | what it reads |", "|---|---|---|---|"], 0
    text = {**BODIES[body].sensor_text, **TASKS["walk"].sensor_text}
    for name, width in observation(body).items():
        span = f"{at}" if width == 1 else f"{at}–{at + width - 1}"
        rows.append(f"| {span} | `{name}` | {width} | {text[name]} |")
        at += width
    return "\n".join(rows) + "\n"


def with_environment() -> list[str]:
    """The registered bodies that declare a Gymnasium environment."""
    return [name for name, cls in BODIES.items() if cls.environment is not None]


def environments_table() -> str:
    rows = ["| id | body | observation | action |", "|---|---|---|---|"]
    for body in with_environment():
        cls, parts = BODIES[body], observation(body)
        rows.append(f"| `{env_id(body)}` | {cls.environment.about} | `({sum(parts.values())},)` float64: "
                    f"{', '.join(f'`{p}`' for p in parts)} (parts below) | `({len(cls.actuators)},)` "
                    f"{cls.environment.action} |")
    return "\n".join(rows) + "\n"


def observations() -> str:
    """Every environment's observation table, each under its id."""
    return "\n".join(f"`{env_id(body)}`:\n\n{observation_table(body)}" for body in with_environment())


def presets_table() -> str:
    """The shipped presets: controller, optimizer and population, generations and episodes, and the preset's own
    line."""
    from .run.run_config import RunConfig, population_of
    from .core.fileio import read_toml
    from .files.presets import describe, names, path, split_declarations

    rows = ["| preset | controller | optimizer, population | generations × episode | what it is |",
            "|---|---|---|---|---|"]
    for name in names():
        settings, declared = split_declarations(name, read_toml(path(name)))
        c = RunConfig.from_dict(settings, where=f"preset {name}")
        # the optimizer's population setting (CMA-ES's 0: its default, which depends on the genes), else the walkers it
        # evaluates per generation (ES: mirrored pairs and theta's own rows; MAP-Elites: the batch)
        population = getattr(c.options, "population", None)
        population = population_of(c) if population is None else population
        pop = f", {population}" if population else ", its default (CMA-ES: 4 + ⌊3 ln genes⌋)"
        episode = f"{c.generations} × {c.episode.seconds:g} s"
        # a table cell
        what = describe(name).replace("|", "\\|") + (" (needs `--from`)" if declared["needs_start"] else "")
        rows.append(f"| `{name}` | `{c.episode.controller}` | {c.optimizer}{pop} | {episode} | {what} |")
    return "\n".join(rows) + "\n"


def progress_example() -> str:
    """The progress lines the commands print, made by the code that prints them (numbers of an example)."""
    from .core.progress import generation_note, line_text

    evolve = line_text("evolve", 62, 150, "generations", generation_note(
        best=21.012, best_fell=False, this=19.407, this_fell=True, mean=8.311, worst=1.022, evals_per_second=3.1,
        simulated=612, longest=50.0), elapsed=252, left=380)
    other = line_text("robustness", 2460, 4920, "trial-s of 164 trials of 30 s", "", elapsed=24, left=25)
    return f"```\n{evolve}\n{other}\n```\n"


def generated() -> dict[str, str]:
    """Every generated part outside the option tables, by id."""
    sections = {part: component_sections(kind) for kind, (_, part, _) in REGISTRIES.items()}
    return {"presets": presets_table(), "progress": progress_example(), "environments": environments_table(),
            "observations": observations(), "terms": terms.terms_table(), **sections}


def render(text: str) -> str:
    """``text`` (a page of docs/) with every generated table and part replaced by the current code
    (KeyError for a section that names nothing known)."""
    found = tables()
    text = MARKER.sub(lambda m: m.group(1) + found[m["id"]] + m.group(4), text)
    parts = generated()
    return GENERATED.sub(lambda m: m.group(1) + parts[m["id"]] + m.group(4), text)


def sections(text: str) -> list[str]:
    """The ids of the option tables between markers in ``text``, in order."""
    return [m["id"] for m in MARKER.finditer(text)]


def parts(text: str) -> list[str]:
    """The ids of the other generated parts in ``text``, in order."""
    return [m["id"] for m in GENERATED.finditer(text)]


if __name__ == "__main__":
    for page in (USAGE, GYM):
        page.write_text(render(page.read_text()))
