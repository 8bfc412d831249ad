"""What a run reads back: a self-contained checkpoint (the start genome inside), config.json's edits refused by
name, every file a command takes read with limits and checked against the declarations, refusals before any
worker starts, and a stop signal's line saying whether the run is complete.  Each case is one line and exit
status 2, or a run equal to an undisturbed one."""

import json
import shutil
import time

import pytest

from .conftest import cli
from .fault_cases import CHECKPOINT_EDITS, CONFIG_EDITS, DEEP, DIFFERS, GENOME_EDITS, SELECT_DAMAGE, SETTINGS, edit
from .test_faults import RUN, contents, files, one_line_error


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    d = tmp_path_factory.mktemp("fin") / "run"
    assert cli("evolve", *RUN, "--out", d) == 0
    return d


@pytest.fixture
def run(finished, tmp_path):
    d = tmp_path / "run"
    shutil.copytree(finished, d)
    return d


# ---- config.json edited: refused by name
@pytest.mark.parametrize("name", CONFIG_EDITS)
def test_an_edited_config_is_refused_by_name(run, capsys, name):
    change, words = CONFIG_EDITS[name]
    (run / "summary.json").unlink()  # cut before its end
    original = json.loads((run / "config.json").read_text())
    edit(run / "config.json", change)
    before = files(run)
    assert cli("evolve", "--resume", run) == 2
    one_line_error(capsys.readouterr().err, DIFFERS, words(original))
    assert files(run) == before


def test_where_the_episodes_run_may_change(run, capsys):
    edit(run / "config.json", lambda c: {**c, "backend": "thread", "workers": 2})
    assert cli("evolve", "--resume", run) == 0
    assert "already complete" in capsys.readouterr().out


@pytest.mark.parametrize("name", CHECKPOINT_EDITS)
def test_a_checkpoint_edited_or_missing_what_it_always_holds_is_refused(run, capsys, name):
    change, words = CHECKPOINT_EDITS[name]
    edit(run / "checkpoint.json", change)
    before = files(run)
    assert cli("evolve", "--resume", run) == 2
    one_line_error(capsys.readouterr().err, words)
    assert files(run) == before


# ---- the start genome lives in the run directory
def _cut_mid_run(monkeypatch):
    """Stop the run after generation 0's commit, while generation 1 is evaluated (a Ctrl-C in the middle of a run)."""
    import evobiped.run.run as runmod

    step = runmod.Run.step

    def stopped(self, evaluator):
        if self.optimizer.generation == 1:
            raise KeyboardInterrupt
        return step(self, evaluator)

    monkeypatch.setattr(runmod.Run, "step", stopped)
    return "interrupted after generation 0"


def _cut_before_summary(monkeypatch):
    """Stop the run after its last commit, before summary.json (a finished run's last step)."""
    import evobiped.run.run as runmod

    def stop(*a):
        raise KeyboardInterrupt

    monkeypatch.setattr(runmod.Run, "finish", stop)
    return "before summary.json was written; the run is complete once evobiped evolve --resume"


@pytest.mark.parametrize("cut", [_cut_mid_run, _cut_before_summary])
def test_a_run_from_a_relative_path_resumes_anywhere_with_its_source_gone(finished, tmp_path, monkeypatch, capsys, cut):
    """``--from seed.json`` (relative), cut, then ``--resume /abs/path`` from another directory with the seed gone:
    every file equals the uninterrupted run's (individuals.jsonl included)."""
    here, elsewhere = tmp_path / "here", tmp_path / "elsewhere"
    here.mkdir(), elsewhere.mkdir()
    shutil.copy(finished / "best.json", here / "seed.json")
    monkeypatch.chdir(here)
    assert cli("evolve", *RUN, "--from", "seed.json", "--out", "whole") == 0
    said = cut(monkeypatch)
    assert cli("evolve", *RUN, "--from", "seed.json", "--out", "cut") == 130
    assert said in capsys.readouterr().err
    monkeypatch.undo()
    (here / "seed.json").unlink()
    monkeypatch.chdir(elsewhere)
    assert (here / "cut").resolve().is_absolute()
    assert cli("evolve", "--resume", (here / "cut").resolve(), "--quiet") == 0
    assert cli("evolve", "--resume", (here / "whole").resolve(), "--quiet") == 0
    assert "started from" not in capsys.readouterr().err
    assert contents(here / "cut") == contents(here / "whole")
    assert (here / "cut" / "individuals.jsonl").read_bytes() == (here / "whole" / "individuals.jsonl").read_bytes()
    assert json.loads((here / "whole" / "start.json").read_text())["source"] == "seed.json"


def test_a_start_genome_that_differs_from_the_config_is_refused(finished, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    shutil.copy(finished / "best.json", tmp_path / "seed.json")
    assert cli("evolve", *RUN, "--from", "seed.json", "--out", "r") == 0
    edit(tmp_path / "r" / "checkpoint.json", lambda ck: {**ck, "start": [True] * len(ck["start"])})
    assert cli("evolve", "--resume", "r") == 2
    one_line_error(capsys.readouterr().err, "start must be a list of numbers")


# ---- files read with limits and checked against the declarations
def test_deep_nesting_in_any_file_is_one_line(run, tmp_path, capsys):
    (run / "checkpoint.json").write_text(DEEP)
    assert cli("evolve", "--resume", run) == 2
    one_line_error(capsys.readouterr().err, "nested more than 32 deep")
    (tmp_path / "c.toml").write_text("a = " + DEEP + "\n")
    assert cli("evolve", "--config", tmp_path / "c.toml", "--out", tmp_path / "x") == 2
    one_line_error(capsys.readouterr().err, "nested more than 32 deep")
    (tmp_path / "g.json").write_text(DEEP)
    assert cli("replay", tmp_path / "g.json", "--quiet") == 2
    one_line_error(capsys.readouterr().err, "nested more than 32 deep")
    (tmp_path / "g.json").write_text("[" * 40 + "]" * 40)  # parses, but deeper than any file of evobiped's
    assert cli("replay", tmp_path / "g.json", "--quiet") == 2
    one_line_error(capsys.readouterr().err, "nested more than 32 deep")


@pytest.mark.parametrize("name", SETTINGS)
def test_a_hostile_settings_file_is_one_line_before_anything_is_written(tmp_path, capsys, name):
    """Tables of the wrong type (checked before the flags go into them: --cyclic adds task options), nesting, a source
    beyond 10 km, a population beyond the machine's memory."""
    text, words = SETTINGS[name]
    (tmp_path / "c.toml").write_text(text + "\n")
    sizes = [] if "population" in name else ["--population", "4"]
    cyclic = [] if "steer" in text else ["--cyclic"]  # the steer task has no cyclic criterion
    assert cli("evolve", "--config", tmp_path / "c.toml", *sizes, "--episode-seconds", "1", *cyclic, "--backend",
               "thread", "--workers", "2", "--out", tmp_path / "x") == 2
    one_line_error(capsys.readouterr().err, words)
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("name", GENOME_EDITS)
def test_a_malformed_genome_file_is_one_line(run, tmp_path, capsys, name):
    change, words = GENOME_EDITS[name]
    f = tmp_path / "g.json"
    shutil.copy(run / "best.json", f)
    edit(f, change)
    assert cli("replay", f, "--out", tmp_path / "r.rrd", "--quiet") == 2
    one_line_error(capsys.readouterr().err, words)


@pytest.mark.parametrize("name", SELECT_DAMAGE)
def test_select_on_a_damaged_run_is_one_line(run, capsys, name):
    damage, words = SELECT_DAMAGE[name]
    damage(run)
    assert cli("select", run, "--seconds", "1") == 2
    one_line_error(capsys.readouterr().err, words)


def test_an_older_cma_log_longer_than_the_history_is_refused_at_once(tmp_path, capsys):
    d = tmp_path / "cma"
    assert cli("evolve", *RUN, "--optimizer", "cma", "--out", d) == 0
    lam = len(json.loads((d / "checkpoint.json").read_text())["optimizer"]["fitness"])
    edit(d / "checkpoint.json", lambda ck: {**ck,
                                            "optimizer": {"name": "cma", "generation": 20000,
                                                          "told": [[0.0] * lam] * 20000,
                                                                "fitness": [None] * lam}})
    t = time.perf_counter()
    assert cli("evolve", "--resume", d) == 2
    assert time.perf_counter() - t < 10
    one_line_error(capsys.readouterr().err, "history has 2 rows for generation 20000")


# ---- refused before any worker starts or file is written
def test_a_population_beyond_memory_is_refused_before_any_worker(tmp_path, capsys, monkeypatch):
    import evobiped.evaluation.backends as evaluate

    def no_workers(*a, **k):
        raise AssertionError("workers started")

    monkeypatch.setattr(evaluate, "make_evaluator", no_workers)
    assert cli("evolve", "--population", "5000000", "--backend", "thread", "--workers", "2", "--out",
               tmp_path / "x") == 2
    one_line_error(capsys.readouterr().err, "population 5000000 needs about")
    assert not (tmp_path / "x").exists()


def test_a_preset_that_tunes_a_given_genome_needs_from(tmp_path, capsys):
    assert cli("evolve", "--preset", "walker-ctrnn-distilled", "--out", tmp_path / "x") == 2
    one_line_error(capsys.readouterr().err, "--preset walker-ctrnn-distilled: tunes a given genome", "--from")
    assert not (tmp_path / "x").exists()


def test_a_source_beyond_10_km_is_one_line(tmp_path, capsys):
    assert cli("evolve", "--task", "steer", "--source", "1e300", "3", "--out", tmp_path / "x") == 2
    one_line_error(capsys.readouterr().err, "farther than 10000 m")


# ---- a stop signal at the very end says whether the run is complete
def test_a_stop_signal_after_the_last_file_says_the_run_is_complete(tmp_path, capsys, monkeypatch):
    import evobiped.cli.evolving.evolve_cmd as evolve_cmd

    def interrupted(*a):
        raise KeyboardInterrupt

    monkeypatch.setattr(evolve_cmd, "hms", interrupted)  # while the final line is written
    assert cli("evolve", *RUN, "--out", tmp_path / "r") == 130
    err = capsys.readouterr().err
    assert err.count(
        "\n") == 1 and "interrupted after the run completed: all 2 generations and summary.json are written" in err, err
