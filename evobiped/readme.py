"""The option tables of docs/usage.md, generated from the declarations (:mod:`evobiped.options`).

Each table sits between ``<!-- options: ID -->`` and ``<!-- end options -->`` in
docs/usage.md, ID naming the component (``body reil``, ``controller ctrnn``,
``task walk``, ``episode perturbations``, ``optimizer ga``, ``environment``, ...).  ``python -m evobiped.readme`` rewrites
them; tests/test_options.py checks that they agree with the declarations.
"""

from __future__ import annotations

import re
from pathlib import Path

from .bodies import BODIES
from .controllers import CONTROLLERS
from .controllers.base import GENERIC_CONTROLLER_OPTIONS
from .envs.walkers import EnvOptions
from .evolution.cma import CMAOptions
from .evolution.curriculum import CurriculumOptions
from .evolution.es import ESOptions
from .evolution.run_config import NormaliseOptions
from .evolution.ga import GAOptions
from .options import markdown_table
from .perturb import PerturbationOptions
from .tasks import TASKS

#: the page that holds the tables
USAGE = Path(__file__).resolve().parent.parent / "docs" / "usage.md"
#: a generated section: its id, the table
MARKER = re.compile(r"(<!-- options: (?P<id>[a-z0-9_ -]+) -->\n)(?P<table>.*?)(<!-- end options -->)", re.S)


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
    out["run normalise"] = markdown_table(NormaliseOptions)
    out["run curriculum"] = markdown_table(CurriculumOptions)
    out["environment"] = markdown_table(EnvOptions)
    return out


def render(text: str) -> str:
    """``text`` (docs/usage.md) with every generated table replaced by the current declarations
    (KeyError for a section that names no registered component)."""
    found = tables()
    return MARKER.sub(lambda m: m.group(1) + found[m["id"]] + m.group(4), text)


def sections(text: str) -> list[str]:
    """The ids of the generated sections in ``text``, in order."""
    return [m["id"] for m in MARKER.finditer(text)]


if __name__ == "__main__":
    USAGE.write_text(render(USAGE.read_text()))
