"""The generated parts of the documentation: docs/usage.md's option tables, presets table and progress lines,
docs/gym.md's environments and observation parts.

An option table sits between ``<!-- options: ID -->`` and ``<!-- end options -->`` in docs/usage.md, ID naming
the component (``body reil``, ``controller ctrnn``, ``task walk``, ``episode perturbations``, ``optimizer ga``,
``environment``, ...); any other generated part between ``<!-- generated: ID -->`` and ``<!-- end generated -->``
(``presets``, ``progress`` in docs/usage.md; ``environments``, ``observation reil``, ``observation taga`` in
docs/gym.md).  ``python -m evobiped.readme`` rewrites them; tests/test_options.py and tests/test_docs.py check
that they agree with the code.
"""

from __future__ import annotations

import re
from pathlib import Path

from .bodies import BODIES
from .controllers import CONTROLLERS
from .controllers.base import GENERIC_CONTROLLER_OPTIONS
from .envs.walkers import EnvOptions
from .optimizers.cma import CMAOptions
from .run.curriculum import CurriculumOptions
from .run.stopping import RestartOptions, StopOptions
from .optimizers.es import ESOptions
from .optimizers.map_elites import MapElitesOptions
from .run.run_config import NormaliseOptions
from .optimizers.ga import GAOptions
from .core.options import markdown_table
from .physics import gait
from .physics.perturb import PerturbationOptions
from .tasks import TASKS

DOCS = Path(__file__).resolve().parent.parent / "docs"
#: the page that holds the option tables
USAGE = DOCS / "usage.md"
#: the Gymnasium page
GYM = DOCS / "gym.md"
#: a generated option table: its id, the table
MARKER = re.compile(r"(<!-- options: (?P<id>[a-z0-9_ -]+) -->\n)(?P<table>.*?)(<!-- end options -->)", re.S)
#: any other generated part: its id, the text
GENERATED = re.compile(r"(<!-- generated: (?P<id>[a-z0-9_ -]+) -->\n)(?P<table>.*?)(<!-- end generated -->)", re.S)

#: the Gymnasium environments: id -> (body, what it is, its action)
ENVIRONMENTS = {
    "evobiped/ReilBiped-v0": ("reil", "Reil & Husbands' 3D biped", "`(6,)` PD target angles (rad) in Table II's ranges"),
    "evobiped/TagaBiped-v0": ("taga", "Taga's sagittal 5-link biped", "`(6,)` joint torques (N m), ±`max_torque`"),
}

#: what each sensor an observation can hold reads (a body's, a task's), for the observation tables
SENSOR_TEXT = {
    "joint_angles": "joint angles (rad) in action order: left hip pitch, left hip roll, left knee, right hip pitch, "
                    "right hip roll, right knee",
    "joint_velocities": "their rates (rad/s), same order",
    "foot_contact": "foot contacts: left, right (0 or 1)",
    "pelvis_tilt": "pelvis tilt: pitch (+ nose down), roll (+ left side up) (rad)",
    "pelvis_tilt_rate": "their rates (rad/s)",
    "com_from_feet": "centre of mass minus the left foot (forward, left), minus the right foot (forward, left) (m, "
                     "heading frame)",
    "com_velocity": "centre-of-mass velocity: forward, left (m/s, heading frame)",
    "stance_leg": "which leg stands: +1 left, −1 right; it changes at the other foot's touchdown after ≥ 0.06 s "
                  "in the air (`evobiped/physics/gait.py`)",
    "since_touchdown": "seconds since the stance leg's touchdown, capped at 2 s",
    "stance_side": "`stance_leg`'s value, not mirrored in the stance frame: a stance-frame network's way to turn",
    "link_angles": "inertial angles of right thigh, right shank, left thigh, left shank (rad from the horizontal)",
    "link_velocities": "their rates (rad/s), same order",
    "ground_contact": "ground contacts: right, left (0 or 1)",
    "ground_force": "ground forces F_g1..F_g4 (N)",
    "sound": "the steer task's ear signal s (its sensor, after the body's)",
    "command_speed": "the command task's commanded forward speed (m/s)",
    "command_turning": "the command task's commanded turning rate (rad/s, + left; its sign changes in the stance frame's mirror)",
    "command_stop": "the command task's stop: 1 at a zero speed command, else 0",
}


def tables() -> dict[str, str]:
    """Every registered component's option table, by section id."""
    out = {}
    for kind, reg in (("body", BODIES), ("controller", CONTROLLERS), ("task", TASKS)):
        for name, cls in reg.items():
            # every controller's generic options (inputs, genes, latency) are described once, beside the tables
            out[f"{kind} {name}"] = markdown_table(cls.Options, skip=GENERIC_CONTROLLER_OPTIONS if kind == "controller" else ())
    out["episode perturbations"] = markdown_table(PerturbationOptions)
    out["optimizer ga"] = markdown_table(GAOptions)
    out["optimizer cma"] = markdown_table(CMAOptions)
    out["optimizer es"] = markdown_table(ESOptions)
    out["optimizer map-elites"] = markdown_table(MapElitesOptions)
    out["run normalise"] = markdown_table(NormaliseOptions)
    out["run curriculum"] = markdown_table(CurriculumOptions)
    out["run stop"] = markdown_table(StopOptions)
    out["run restart"] = markdown_table(RestartOptions)
    out["environment"] = markdown_table(EnvOptions)
    return out


def observation(body: str, task: str = "walk") -> dict[str, int]:
    """The parts of an environment's observation in order (name -> width): the body's sensors, then the task's
    (those read only on request left out, as the environment does)."""
    return gait.by_default({**BODIES[body].sensor_widths, **TASKS[task]().sensor_widths()})


def observation_table(body: str) -> str:
    """The observation of ``body``'s environment part by part: indices, part, width, what it reads."""
    rows, at = ["| indices | part | width | what it reads |", "|---|---|---|---|"], 0
    for name, width in observation(body).items():
        span = f"{at}" if width == 1 else f"{at}–{at + width - 1}"
        rows.append(f"| {span} | `{name}` | {width} | {SENSOR_TEXT[name]} |")
        at += width
    return "\n".join(rows) + "\n"


def environments_table() -> str:
    rows = ["| id | body | observation | action |", "|---|---|---|---|"]
    for env_id, (body, what, action) in ENVIRONMENTS.items():
        parts = observation(body)
        rows.append(f"| `{env_id}` | {what} | `({sum(parts.values())},)` float64: {', '.join(f'`{p}`' for p in parts)} "
                    f"(parts below) | {action} |")
    return "\n".join(rows) + "\n"


def presets_table() -> str:
    """The shipped presets: controller, optimizer and population, generations and episodes, and the preset's own line."""
    from .run.run_config import RunConfig, population_of
    from .core.fileio import read_toml
    from .files.presets import describe, names, path, split_declarations

    rows = ["| preset | controller | optimizer, population | generations × episode | what it is |", "|---|---|---|---|---|"]
    for name in names():
        settings, declared = split_declarations(name, read_toml(path(name)))
        c = RunConfig.from_dict(settings, where=f"preset {name}")
        # the optimizer's population setting (CMA-ES's 0: its default, which depends on the genes), else the walkers it
        # evaluates per generation (ES: mirrored pairs and theta's own rows; MAP-Elites: the batch)
        population = getattr(c.options, "population", None)
        population = population_of(c) if population is None else population
        pop = f", {population}" if population else ", its default (CMA-ES: 4 + ⌊3 ln genes⌋)"
        episode = f"{c.generations} × {c.episode.seconds:g} s"
        what = describe(name).replace("|", "\\|") + (" (needs `--from`)" if declared["needs_start"] else "")  # a table cell
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
    out = {"presets": presets_table(), "progress": progress_example(), "environments": environments_table()}
    for body in {b for b, _, _ in ENVIRONMENTS.values()}:
        out[f"observation {body}"] = observation_table(body)
    return out


def render(text: str) -> str:
    """``text`` (a page of docs/) with every generated table and part replaced by the current code
    (KeyError for a section that names nothing known)."""
    found = tables()
    text = MARKER.sub(lambda m: m.group(1) + found[m["id"]] + m.group(4), text)
    parts = generated()
    return GENERATED.sub(lambda m: m.group(1) + parts[m["id"]] + m.group(4), text)


def sections(text: str) -> list[str]:
    """The ids of the generated option tables in ``text``, in order."""
    return [m["id"] for m in MARKER.finditer(text)]


def parts(text: str) -> list[str]:
    """The ids of the other generated parts in ``text``, in order."""
    return [m["id"] for m in GENERATED.finditer(text)]


if __name__ == "__main__":
    for page in (USAGE, GYM):
        page.write_text(render(page.read_text()))
