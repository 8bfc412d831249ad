"""The damage both the fault tests and the release campaign (tests/fault_campaign.py) do, in one place: edits of a
run's config.json and checkpoint, settings files, genome files and damaged runs for ``select``, each with the words
of the one line that must refuse it.  Every edit is relative to the run it damages (``seed + 1``, the first genes),
so one table serves the tests' tiny run and the campaign's."""

from __future__ import annotations

import csv
import json
from pathlib import Path

#: a JSON (or TOML value) nested 100,000 deep: every reader refuses it by its depth
DEEP = "[" * 100_000 + "]" * 100_000
#: how a resume refuses an edited config.json
DIFFERS = "config.json differs from the one this checkpoint was made with"


def edit(path: Path, change) -> None:
    """Rewrite the JSON file ``path`` as ``change(its table)``."""
    path.write_text(json.dumps(change(json.loads(path.read_text()))))


#: config.json edits: name -> (change of the table, the original table -> what the refusal names after DIFFERS)
CONFIG_EDITS = {
    "seed": (lambda c: {**c, "seed": c["seed"] + 1}, lambda c: f"seed {c['seed']} → {c['seed'] + 1}"),
    "generations": (lambda c: {**c, "generations": c["generations"] + 1},
                    lambda c: f"generations {c['generations']} → {c['generations'] + 1}"),
    "body": (lambda c: {**c, "episode": {**c["episode"], "body": "taga"}}, lambda c: 'episode.body "reil" → "taga"'),
    "episode seconds": (lambda c: {**c, "episode": {**c["episode"], "seconds": c["episode"]["seconds"] * 2}},
                        lambda c: f"episode.seconds {c['episode']['seconds']} → {c['episode']['seconds'] * 2}"),
    "perturbations": (lambda c: {**c, "episode": {**c["episode"], "perturbations": {"presentations": 2}}},
                      lambda c: "episode.perturbations"),
    "environment": (lambda c: {**c, "environment": {**c["environment"], "numpy": "1.0"}},
                    lambda c: 'environment.numpy "'),
    "population": (lambda c: {**c, "ga": {**c["ga"], "population": c["ga"]["population"] + 2}},
                   lambda c: f"ga.population {c['ga']['population']} → {c['ga']['population'] + 2}"),
    "start genome added": (lambda c: {**c, "initial": "elsewhere.json"}, lambda c: 'initial null → "elsewhere.json"'),
}

#: checkpoint.json edits: name -> (change of the table, words of the refusal)
CHECKPOINT_EDITS = {
    "empty population": (lambda ck: {**ck, "optimizer": {**ck["optimizer"], "population": [], "fitness": []}},
                         "ga.population must be a non-empty list"),
    "outcome deleted": (lambda ck: {k: v for k, v in ck.items() if k != "outcome"}, "outcome is missing"),
    "history terms deleted": (lambda ck: {k: v for k, v in ck.items() if k != "history_terms"},
                              "history_terms is missing"),
    "best walk deleted": (lambda ck: {k: v for k, v in ck.items() if k != "best_walk"}, "best_walk is missing"),
    "start deleted": (lambda ck: {k: v for k, v in ck.items() if k != "start"}, "start is missing"),
    "outcome.walk deleted": (lambda ck: {**ck, "outcome": {k: v for k, v in ck["outcome"].items() if k != "walk"}},
                             "outcome must hold fell, unstable, end_time and walk"),
    "start genome of booleans": (lambda ck: {**ck, "start": [True] * len(ck["best_genome"])},
                                 "names no start genome (initial)"),
    "settings a number": (lambda ck: {**ck, "settings": 5}, "the recorded settings are not a table"),
    "best NaN": (lambda ck: {**ck, "best": {**ck["best"], "fitness": float("nan")}},
                 "best.fitness must be finite, got nan"),
    "history row short": (lambda ck: {**ck, "history": [r[:3] for r in ck["history"]]},
                          "history[0] must be a list of 9 values"),
    "population of strings": (lambda ck: {**ck, "optimizer": {**ck["optimizer"],
                                                              "population": [["x"] * len(ck["best_genome"])] * 8}},
                              "ga.population must be a non-empty list of rows of"),
    "genome of booleans": (lambda ck: {**ck, "best_genome": [True] * len(ck["best_genome"])},
                           "best_genome[0] must be a number, got True"),
}

#: settings files for ``evolve --config``: name -> (the file's text, words of the refusal)
SETTINGS = {
    "100,000-deep TOML": ("a = " + DEEP, "nested more than 32 deep"),
    "episode = 5": ("episode = 5", "episode: must be a table"),
    "ga = [1, 2]": ("ga = [1, 2]", "ga: must be a table"),
    "cma = 3": ("cma = 3", "cma: must be a table"),
    "task_options a number": ("[episode]\ntask_options = 3", "episode.task_options: must be"),
    "a source at 1e300 m": ('[episode]\ntask = "steer"\n[episode.task_options]\nsources = [[1e300, 3]]',
                            "farther than 10000 m"),
    "population 5 million": ("[ga]\npopulation = 5000000", "population 5000000 needs about"),
}

#: genome files for ``replay``, made from a run's best.json: name -> (change of its table, words of the refusal)
GENOME_EDITS = {
    "genome of booleans": (lambda g: {**g, "genome": [True] * len(g["genome"])}, "'genome' must be a list of numbers"),
    "short genome": (lambda g: {**g, "genome": g["genome"][:5]}, "has 5 genes, the layout needs"),
    "outcome rows not a list": (lambda g: {**g, "outcome": {"fell": False, "rows": 5}}, "'outcome' must be"),
    "outcome rows of strings": (lambda g: {**g, "outcome": {"fell": False, "rows": [{"distance": "far"}]}},
                                "'outcome' must be"),
    "gene 1e300": (lambda g: {**g, "genome": [1e300] + g["genome"][1:]}, "= 1e+300 is outside"),
}


def _generation(d: Path, g: int, change) -> None:
    edit(d / "generations" / f"gen_{g:04d}.json", change)


def _nan_best(path: Path) -> None:
    """history.csv with row 1's best fitness NaN."""
    rows = list(csv.reader(path.read_text().splitlines()))
    rows[1][1] = "nan"
    path.write_text("".join(",".join(r) + "\n" for r in rows))


def _before_digests(ck: dict) -> dict:
    """A checkpoint as written before it kept the generation files' digests (and before its format)."""
    return {k: v for k, v in ck.items() if k not in ("generation_digests", "format")}


#: run directories damaged for ``select``: name -> (damage of the directory, words of the refusal)
SELECT_DAMAGE = {
    "a short genome in a generation file": (lambda d: _generation(d, 0, lambda g: {**g, "genome": g["genome"][:7]}),
                                            "gen_0000.json is not the file its generation committed"),
    "generation files of mixed controllers": (
        lambda d: _generation(d, 0, lambda g: {**g, "episode": {**g["episode"], "controller": "matsuoka"}}),
                                              "gen_0000.json is not the file its generation committed"),
    "another episode": (lambda d: _generation(d, 0, lambda g: {**g, "episode": {**g["episode"], "seconds": 9.0}}),
                        "gen_0000.json is not the file its generation committed"),
    # a checkpoint written before it kept the generation files' digests: their generation and fitness agree
    "another episode, older checkpoint": (lambda d: (edit(d / "checkpoint.json", _before_digests),
                                                     _generation(d, 1,
                                                                 lambda g: {**g,
                                                                            "episode": {**g[
                                                                                "episode"], "seconds": 9.0}})),
                                          "of another episode than the run's"),
    "config names a number as its start genome": (lambda d: edit(d / "config.json", lambda c: {**c, "initial": 5}),
                                                  "initial: must be a non-empty string"),
    "a NaN best in history.csv": (lambda d: _nan_best(d / "history.csv"), "best of row 1 is nan, not a fitness"),
}

#: a commanded walker shipped with the repository (from its root), for the commands that read one before they refuse
COMMANDED = "docs/walkers/ctrnn_command_seed1.json"
#: numbers a command must refuse before any work: name -> (the command's arguments, words of the refusal); ``{root}``
#: stands for the repository's root, ``{tmp}`` for a folder that must stay empty.  None reaches a simulation.
NUMBERS = {
    "taga --push-delay inf": (["taga", "--push", "leg", "--push-delay", "inf"],
                              "--push-delay: must be a finite number"),
    "taga --push-delay nan": (["taga", "--push", "hip", "--push-delay", "nan"],
                              "--push-delay: must be a finite number"),
    "taga --push-delay 1e300": (["taga", "--push", "leg", "--push-delay", "1e300"], "from 0 to 2 s"),
    "taga --push-delay -1": (["taga", "--push", "leg", "--push-delay", "-1"], "from 0 to 2 s"),
    "taga --push-force nan": (["taga", "--push", "leg", "--push-force", "nan"],
                              "--push-force: must be a finite number"),
    "taga --push-force 1e300": (["taga", "--push", "hip", "--push-force", "1e300"], "from 0 to 10000 N"),
    "taga --push-force -inf": (["taga", "--push", "leg", "--push-force", "-inf"],
                               "--push-force: must be a finite number"),
    "taga --seconds 1e12": (["taga", "--seconds", "1e12"], "--seconds must be <= 3600 s"),
    "taga --u0 nan": (["taga", "--u0", "nan"], "--u0: must be a finite number"),
    "adapt --rho 1e-300": (["adapt", "RUN", "--damage", "weak:hip:0.5", "--rho", "1e-300"], "from 0.001 to 1000"),
    "adapt --rho inf": (["adapt", "RUN", "--damage", "weak:hip:0.5", "--rho", "inf"], "--rho: must be a finite number"),
    "adapt --pose-noise 1e300": (["adapt", "RUN", "--damage", "weak:hip:0.5", "--pose-noise", "1e300"],
                                 "from 0 to 0.5 rad"),
    "adapt --pose-noise nan": (["adapt", "RUN", "--damage", "weak:hip:0.5", "--pose-noise", "nan"],
                               "--pose-noise: must be a finite"),
    "adapt --seed -1": (["adapt", "RUN", "--damage", "weak:hip:0.5", "--seed", "-1"],
                        "--seed: must be a whole number from 0"),
    "episode --seed -1": (["episode", "--seed", "-1"], "--seed: must be a whole number from 0"),
    "episode --seed 1e300": (["episode", "--seed", "1e300"], "--seed: must be a whole number from 0 to 2^63 - 1"),
    "gait --battery --seed -1": (["gait", "{root}/" + COMMANDED, "--battery", "2", "--seed", "-1"],
                                 "--seed: must be a whole"),
    "gait --battery 1e8 --stretches 1e8": (["gait", "{root}/" + COMMANDED, "--battery", "1e8", "--stretches", "1e8"],
                                           "--battery: must be a whole number from 1 to 10,000"),
    "gait --battery 10000 --stretches 10000": (["gait", "{root}/" + COMMANDED, "--battery", "10000", "--stretches",
                                                "10000"],
                                               "a battery runs at most 100,000"),
    "gait --speed 0.3,1e300": (["gait", "{root}/" + COMMANDED, "--speed", "0.3,1e300"], "within -10 to 10 m/s"),
    "gait --turning 1e9": (["gait", "{root}/" + COMMANDED, "--speed", "0.3", "--turning", "1e9"],
                           "within -720 to 720 deg/s"),
    "command-calibrate --speeds 0.3,1e300": (["genome", "command-calibrate", "{root}/" + COMMANDED, "{tmp}/out.json",
                                              "--speeds", "0.3,1e300"],
                                             "--speeds: each value must be within -10 to 10 m/s"),
    "genome ranges --block -1e308 1e308": (["genome", "ranges", "{root}/docs/walkers/ctrnn_walk_seed1.json",
                                            "{tmp}/out.json",
                                            "--block", "weights", "-1e308", "1e308"],
                                           "must be finite and at most 1.8e308 wide"),
    "g3 --sweep 0 1 1e-12": (["g3", "fig4", "--sweep", "0", "1", "1e-12"], "a sweep runs at most 10,000"),
    "g3 --from-go inf": (["g3", "fig4", "--from-go", "inf"], "--from-go: must be a finite number"),
    "g3 --from-go -1": (["g3", "fig4", "--from-go", "-1"], "--from-go: a GO level must be >= 0, got -1"),
    "g3 --dt 1e-9": (["g3", "fig4", "--dt", "1e-9"], "RK4 steps, more than 1e+07"),
    "g3 --t-run 1e12": (["g3", "fig4", "--t-run", "1e12"], "RK4 steps, more than 1e+07"),
    "g3 --reproduce --step 1e-12": (["g3", "--reproduce", "{tmp}/g3", "--step", "1e-12"],
                                    "--step: must be from 0.001 to 1"),
    "compare --first-seed -3": (["compare", "A", "--seeds", "2", "--first-seed", "-3"],
                                "--first-seed: must be a whole number"),
    "robustness --phase-seed -1": (["robustness", "RUN", "--phase-seed", "-1"], "--phase-seed: must be a whole number"),
    "distill --seed -1": (["distill", "RUN", "--seed", "-1"], "--seed: must be a whole number from 0"),
}


def number_case(name: str, root: Path, tmp: Path) -> tuple[list[str], str]:
    """The arguments of :data:`NUMBERS`' case ``name`` with its paths filled in, and the words of its refusal."""
    args, words = NUMBERS[name]
    return [a.format(root=root, tmp=tmp) for a in args], words
