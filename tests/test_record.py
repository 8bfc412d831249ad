"""The run's record (checkpoint.json, :mod:`evobiped.files.rundir.record`): each older format upgraded step by step
to the current one, the current one read back exactly, and one line naming the first bad field."""

import json
import shutil
from pathlib import Path

import pytest

from evobiped.core.errors import UserError
from evobiped.core.fileio import read_json
from evobiped.files import rundir
from evobiped.files.rundir.record import format_of
from evobiped.run import Run, RunConfig
from evobiped.run.run_config import make_optimizer

FIXTURES = Path(__file__).parent / "fixtures" / "rundirs"
FORMATS = sorted(p.name for p in FIXTURES.iterdir() if p.is_dir())


def _config(d: Path) -> RunConfig:
    cfg = json.loads((d / "config.json").read_text())
    return RunConfig.from_dict({k: v for k, v in cfg.items() if k not in ("evobiped", "environment")}, where="config")


def _read(d: Path, table) -> rundir.RunRecord:
    opt = make_optimizer(_config(d))
    return rundir.RunRecord.from_dict(table, generations=5, low=opt.low, high=opt.high)


@pytest.mark.parametrize("name", FORMATS)
def test_each_older_format_is_told_and_upgraded_to_a_valid_record(name):
    d = FIXTURES / name / "run"
    raw = json.loads((d / "checkpoint.json").read_text())
    assert "format" not in raw and format_of(raw) == int(name.split("-")[0].removeprefix("format"))
    table = rundir.upgrade(raw, d, settings={"seed": 0}, start=lambda: None)
    record = _read(d, table)
    assert record.to_dict() == table and record.settings == raw.get("settings", {"seed": 0})
    assert len(record.history) == len(record.history_terms) == len(record.generation_digests) == 2
    assert record.best_genome == json.loads(rundir.generation_file(d, record.best["generation"]).read_text())["genome"]
    assert record.optimizer == raw.get("optimizer", raw.get("ga"))


def test_the_first_format_takes_its_best_genome_from_its_generation_file(tmp_path):
    d = tmp_path / "run"
    shutil.copytree(FIXTURES / "format1-b28be9c" / "run", d)
    raw = json.loads((d / "checkpoint.json").read_text())
    rundir.generation_file(d, raw["best"]["generation"]).unlink()
    with pytest.raises(UserError, match=r"best_genome is missing, and gen_0001.json, which holds it, cannot be read"):
        rundir.upgrade(raw, d, settings={}, start=lambda: None)


def test_a_current_record_is_read_back_exactly_and_not_upgraded(tmp_path):
    d = tmp_path / "run"
    shutil.copytree(FIXTURES / "format7-630077b" / "run", d)
    Run.resume(d).close()  # a resume writes no checkpoint: it stays in the older format
    table = read_json(d / "checkpoint.json", what="checkpoint", file_format=rundir.FORMAT)
    assert "format" not in table
    with Run.resume(d) as run:
        record = run.record
    table = record.to_dict()
    assert table["format"] == rundir.FORMAT and rundir.upgrade(table, d) is table
    assert _read(d, json.loads(json.dumps(table))) == record


@pytest.mark.parametrize("key", ["optimizer", "history", "best", "wall_seconds", "best_genome", "outcome",
                                 "history_terms", "best_walk", "start", "settings", "generation_digests", "format"])
def test_a_current_record_lacking_a_field_names_it(key):
    d = FIXTURES / "format7-630077b" / "run"
    table = rundir.upgrade(json.loads((d / "checkpoint.json").read_text()), d)
    table.pop(key)
    with pytest.raises(UserError, match=f"^{key} (is missing|must be evobiped-checkpoint/8, got None)$"):
        _read(d, table)


@pytest.mark.parametrize("change, words", [
    (lambda t: {**t, "best_genome": None}, "best_genome must be a list of"),
    (lambda t: {**t, "history_terms": t["history_terms"][:1]}, "history_terms must be a list of tables of numbers"),
    (lambda t: {**t, "generation_digests": ["ab"] * 2}, "generation_digests must hold SHA-256 digests"),
    (lambda t: {**t, "settings": []}, "settings must be a table"),
    (lambda t: {**t, "start": [True]}, "start must be a list of numbers"),
])
def test_a_bad_field_is_one_line_naming_it(change, words):
    d = FIXTURES / "format7-630077b" / "run"
    table = rundir.upgrade(json.loads((d / "checkpoint.json").read_text()), d)
    with pytest.raises(UserError, match=words):
        _read(d, change(table))


def test_a_checkpoint_of_another_format_is_refused_by_name(tmp_path):
    d = tmp_path / "run"
    shutil.copytree(FIXTURES / "format7-630077b" / "run", d)
    ck = json.loads((d / "checkpoint.json").read_text())
    (d / "checkpoint.json").write_text(json.dumps({**ck, "format": "evobiped-checkpoint/9"}))
    words = "is in format 'evobiped-checkpoint/9'; this evobiped reads evobiped-checkpoint/8"
    with pytest.raises(UserError, match=words):
        Run.resume(d)
