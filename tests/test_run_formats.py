"""Every run directory the project has ever written resumes: one real run directory of each older checkpoint format
(``tests/fixtures/rundirs``, made by the code that wrote that format, interrupted after two of five generations)
continues with the current code exactly as the uninterrupted run of its own code did."""

import csv
import json
import shutil
from pathlib import Path

import pytest

from evobiped.evaluation import make_evaluator
from evobiped.files.rundir import HISTORY_COLUMNS
from evobiped.run import Run

FIXTURES = Path(__file__).parent / "fixtures" / "rundirs"
FORMATS = sorted(p.name for p in FIXTURES.iterdir() if p.is_dir())


def _fixed_columns(path: Path) -> list[list[str]]:
    """history.csv's HISTORY_COLUMNS but the wall-clock seconds, one list per generation."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [[r[c] for c in HISTORY_COLUMNS if c != "wall_seconds"] for r in rows]


def test_there_is_a_run_directory_of_each_older_format():
    assert [name.split("-")[0] for name in FORMATS] == [f"format{n}" for n in (1, 2, 3, 4, 5, 6, 7, 7)]


@pytest.mark.parametrize("name", FORMATS)
def test_a_run_of_an_older_format_resumes_and_continues_as_it_would_have(tmp_path, name):
    d = tmp_path / name
    shutil.copytree(FIXTURES / name / "run", d)
    with Run.resume(d) as run, make_evaluator(run.config.episode, "serial") as ev:
        assert run.optimizer.generation == 2
        run.evolve(ev)
    old = FIXTURES / name / "uninterrupted"
    now, then = _fixed_columns(d / "history.csv"), _fixed_columns(old / "history.csv")
    if name.startswith("format1-"):
        # the first format's runs resumed (by this code, as by the code before the record, 630077b) differ from their
        # uninterrupted run in the mean, median and worst of the generation after the resume, never in its best
        now, then = ([r[:2] for r in rows[:3]] + rows[3:] for rows in (now, then))
    assert now == then
    best, then = (json.loads((p / "best.json").read_text()) for p in (d, old))
    keys = ("genome", "fitness", "generation")
    assert [best[k] for k in keys] == [then[k] for k in keys]
    assert (d / "summary.json").is_file() and len(list((d / "generations").glob("gen_*.json"))) == 5
