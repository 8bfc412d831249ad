"""Fine-tuning a walker with evolution strategies: a run --from a genome file starts its running normaliser from the
normaliser the file froze (by input name), so the seed walker meets the inputs it was evolved with."""

import tomllib

import numpy as np

from evobiped.run import RunConfig
from evobiped.run.run_context import RunContext
from evobiped.files.genome_file import load_genome
from evobiped.files.presets import path as preset_path

from .conftest import WALKERS, cli

SEED = WALKERS / "ctrnn_es_seed5.json"


def _config(**changes) -> RunConfig:
    table = tomllib.loads(preset_path("walker-ctrnn-es").read_text())
    table.update({"backend": "serial", "seed": 0})
    for k, v in changes.items():
        table[k] = v
    return RunConfig.from_dict(table)


def test_a_run_from_a_genome_file_starts_from_its_normaliser():
    _, cfg, _ = load_genome(SEED)
    frozen = cfg.controller_options.input_norm
    started = RunContext(_config(initial=str(SEED)), cfg).now()
    assert started.norm_count == frozen["count"]
    assert np.allclose(started.norm[0], frozen["mean"], rtol=0, atol=1e-12)
    assert np.allclose(started.norm[1], frozen["std"], rtol=1e-9)
    fresh = RunContext(_config()).now()  # without --from: the declared centres and scales, as before
    assert fresh.norm_count == 0 and not np.allclose(fresh.norm[1], frozen["std"])


def test_inputs_are_matched_by_name_and_a_new_input_starts_at_its_declared_norm():
    """The run reads the seed's inputs less its first (heading_error) and plus the pelvis height: every shared input
    keeps the seed's centre and scale, shifted to its new place; the new one is declared."""
    _, cfg, _ = load_genome(SEED)
    frozen = cfg.controller_options.input_norm
    table = tomllib.loads(preset_path("walker-ctrnn-es").read_text())
    inputs = table["episode"]["controller_options"]["inputs"][1:]
    table["episode"]["controller_options"]["inputs"] = inputs
    table.update({"backend": "serial", "seed": 0, "initial": str(SEED)})
    config = RunConfig.from_dict(table)
    ctx = RunContext(config, cfg)
    mean, std = ctx.now().norm
    assert len(mean) == len(frozen["mean"]) - 1
    assert np.allclose(mean, frozen["mean"][1:]) and np.allclose(std, frozen["std"][1:])
    declared = RunContext(RunConfig.from_dict({**table, "initial": None})).now().norm
    assert not np.allclose(declared[1], std)


def test_without_a_running_normaliser_nothing_is_seeded():
    ctx = RunContext(_config(initial=str(SEED), normalise={"running": False}), load_genome(SEED)[1])
    assert ctx.stats is None and ctx.now().norm is None


def test_evolve_runs_an_es_preset_from_a_walker_on_the_command_line(tmp_path):
    """`evobiped evolve --preset walker-es-robust --from WALKER` (the command-line evaluator passes the run's context
    on): generation 0's theta is the seed walker, normalised as it was evolved, so it stays up its (shortened)
    episode."""
    import csv
    import json

    from .conftest import cli

    out = tmp_path / "run"
    assert cli("evolve", "--preset", "walker-es-robust", "--from", SEED, "--generations", "1", "--seconds", "3",
               "--backend", "serial", "--seed", "0", "--out", out, "--quiet") == 0
    rows = list(csv.DictReader((out / "history.csv").open()))
    assert len(rows) == 1 and float(rows[0]["evaluation_up"]) == 1.0
    ck = json.loads((out / "checkpoint.json").read_text())
    assert ck["normaliser"]["count"] > load_genome(SEED)[1].controller_options.input_norm["count"]


def test_the_shipped_robust_walker_reaches_its_documented_random_phase_battery():
    """ctrnn_es_robust_seed0 (walker-es-robust, seed 0, generation 74) on the battery with pushes at random phases (seed
    2, after 12.5 s): its recorded figures, one trial per family allowed to tip; the targets it meets, met."""
    import json

    from evobiped.analysis.robustness import battery, summarise

    documented = json.loads((WALKERS / "ctrnn_es_robust_seed0_phases2_robustness.json").read_text())
    genome, cfg, _ = load_genome(WALKERS / "ctrnn_es_robust_seed0.json")
    rows = summarise(battery(cfg.nominal().build(), genome, seconds=documented["seconds"],
                             push_after=documented["push_after"], phase_seed=documented["phase_seed"]))
    got = {r["family"]: r["survived"] for r in rows}
    want = {r["family"]: r["survived"] for r in documented["families"]}
    assert got.keys() == want.keys() and all(abs(got[f] - want[f]) <= 1 for f in want), (got, want)
    assert got["push 10 N"] >= 0.95 * 32 - 1 and got["push 15 N"] >= 0.75 * 32 and got["offset 0.05 rad"] == 8
    assert got["slope 3 %"] == 4


def test_the_shipped_hearing_ctrnn_reaches_both_paper_sources_and_stays_up():
    """steer_ctrnn_es_seed0 passes within 0.5 m of (10, 3) and (10, -3) m and is still up 50 s after (it circles
    them)."""
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location("steer_check",
                                                  Path(__file__).resolve().parent.parent / "scripts" / "steer_check.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    rows = mod.check(WALKERS / "steer_ctrnn_es_seed0.json", [(10.0, 3.0), (10.0, -3.0)], 65.0, 0.5)
    assert all(r["arrived_s"] is not None and r["arrived_s"] < 15 and not r["fell"] and r["up_after_arrival_s"] >= 50
               for r in rows), rows


def test_a_run_from_a_walker_resumed_elsewhere_keeps_its_seeded_normaliser(tmp_path, monkeypatch):
    """The run directory keeps the start genome in its source's episode (start.json, with the frozen normaliser): a run
    cut before its first commit and resumed from another directory, the source gone, starts from the same statistics."""
    import shutil

    from evobiped.run import Run

    (tmp_path / "a").mkdir()
    shutil.copy(SEED, tmp_path / "a" / "seed.json")
    monkeypatch.chdir(tmp_path / "a")
    config = _config(initial="seed.json")
    run = Run.create(tmp_path / "run", config)
    first = run.context.now()
    run.close()
    (tmp_path / "a" / "seed.json").unlink()
    monkeypatch.chdir(tmp_path)
    again = Run.resume(tmp_path / "run")  # no checkpoint yet: it starts over from start.json
    later = again.context.now()
    again.close()
    assert later.norm_count == first.norm_count > 0
    assert np.array_equal(later.norm[0], first.norm[0]) and np.array_equal(later.norm[1], first.norm[1])


def _gene_ranges(*argv) -> int:
    return cli("genome", "ranges", *argv)


TIGHT = ["--block", "weights", -2, 2, "--block", "biases", -1, 1, "--block", "input_weights", -1.5, 1.5,
         "--block", "direct_biases", -1, 1, "--block", "direct_weights", -1, 1]


def test_a_walker_declared_with_tight_ranges_is_the_same_walker_and_the_battery_noise_is_smaller(tmp_path):
    """ctrnn_es_robust_seed0_tight is evobiped genome ranges' output: the shipped genes, the same episode, ranges 8
    (recurrent weights) to 5 (direct) times narrower; the battery's 1 % gene noise draws on the paper's ranges fell it
    in all 8."""
    from evobiped.analysis.robustness import GENE_NOISE, GENE_NOISE_DRAWS, GENE_NOISE_SEED

    robust = WALKERS / "ctrnn_es_robust_seed0.json"
    out = tmp_path / "t.json"
    assert _gene_ranges(robust, out, *TIGHT) == 0
    g, cfg, _ = load_genome(robust)
    gt, ct, _ = load_genome(WALKERS / "ctrnn_es_robust_seed0_tight.json")
    assert np.array_equal(gt, g) and np.array_equal(load_genome(out)[0], g) and ct == load_genome(out)[1]
    paper, tight = cfg.build(), ct.build()
    span = {n: (paper.controller.layout.high
                - paper.controller.layout.low)[s] / (tight.controller.layout.high - tight.controller.layout.low)[s]
            for n, s in paper.controller.layout.slices().items()}
    assert (span["weights"] == 8.0).all() and (span["direct_weights"] == 5.0).all() and (span[
        "time_constants"] == 1.0).all()
    a, b = paper.run(g, seconds=5.0), tight.run(g, seconds=5.0)
    assert np.array_equal(a.end_position, b.end_position)
    noise = np.random.default_rng(GENE_NOISE_SEED).normal(0.0, GENE_NOISE, (GENE_NOISE_DRAWS, g.size))
    fell = paper.run(paper.controller.layout.jitter(np.tile(g, (GENE_NOISE_DRAWS, 1)), noise), seconds=10.0).fell
    assert fell.all()


def test_gene_ranges_refuses_a_range_that_would_clip_a_gene(tmp_path, capsys):
    out = tmp_path / "t.json"
    assert _gene_ranges(WALKERS / "ctrnn_es_robust_seed0.json", out, "--block", "weights", -0.5, 0.5) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "clipped" in err[0] and not out.exists()
    assert _gene_ranges(WALKERS / "ctrnn_es_robust_seed0.json", out, "--block", "weights", 2,
                        -2) == 2 and not out.exists()
