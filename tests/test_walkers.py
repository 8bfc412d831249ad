"""The walkers shipped in docs/walkers: each still walks as docs/walkers.md says, and still
reaches its documented robustness-battery figures (docs/walkers/<name>_robustness.json)."""

import dataclasses
import json
from pathlib import Path

import pytest

from evobiped.genome_file import load_genome
from evobiped.robustness import battery, summarise

WALKERS = Path(__file__).parents[1] / "docs" / "walkers"
#: name -> (least distance in the first 50 s (m), largest |heading| (deg) from the initial facing)
FORWARD_WALKERS = {"simbicon_cma_seed5": (35.0, 10.0), "simbicon_cma_seed3": (25.0, 20.0)}


@pytest.mark.parametrize("name", sorted(FORWARD_WALKERS))
def test_a_forward_walker_walks_forwards_and_stays_up_200_s(name):
    genome, cfg, meta = load_genome(WALKERS / f"{name}.json")
    first = cfg.nominal().build().run(genome)
    walk = first.walk()
    least, widest = FORWARD_WALKERS[name]
    assert not first.fell[0] and first.fitness[0] == pytest.approx(meta["fitness"], rel=1e-9)
    assert walk["distance"] >= least and abs(walk["heading_deg"]) <= widest
    long = dataclasses.replace(cfg.nominal(), seconds=200.0).build().run(genome)
    assert not long.fell[0] and long.end_time[0] == 200.0


@pytest.mark.parametrize("name", sorted(p.stem.removesuffix("_robustness") for p in WALKERS.glob("*_robustness.json")))
def test_a_shipped_walker_still_reaches_its_documented_battery_figures(name):
    documented = json.loads((WALKERS / f"{name}_robustness.json").read_text())
    genome, cfg, _ = load_genome(WALKERS / f"{name}.json")
    rows = summarise(battery(cfg.nominal().build(), genome, seconds=documented["seconds"], push_after=documented["push_after"]))
    got = {r["family"]: r["survived"] for r in rows}
    assert got == {r["family"]: r["survived"] for r in documented["families"]}


def test_a_forward_fitness_walker_replays_with_its_fitness_so_far(tmp_path, capsys):
    """The recording reads the forward fitness every tick: a walker still up counts as up to the end."""
    from evobiped.cli import main

    assert main(["replay", str(WALKERS / "simbicon_cma_seed5.json"), "--seconds", "2", "--out", str(tmp_path / "r.rrd"), "--quiet"]) == 0
    assert (tmp_path / "r.rrd").stat().st_size > 0


def test_the_shipped_steering_walker_reaches_both_paper_sources_without_falling():
    """docs/walkers/steer_simbicon_seed0.json: within 1.0 m of (10, 3) and of (10, -3) m after 50 s, up all the way."""
    import numpy as np

    genome, cfg, meta = load_genome(WALKERS / "steer_simbicon_seed0.json")
    assert cfg.task == "steer" and cfg.task_options.get("sources") is None  # the paper's two sources, the default
    r = cfg.build().run(genome)
    rows = r.rows
    assert not rows.fell.any() and np.all(rows.end_time == 50.0)
    distances = np.linalg.norm(rows.end_position - np.array([[10.0, 3.0], [10.0, -3.0]]), axis=1)
    assert np.all(distances < 1.0)
    assert r.fitness[0] == pytest.approx(-distances.mean()) == pytest.approx(meta["fitness"], rel=1e-9)


def test_the_six_source_steering_walker_reaches_sources_it_never_heard():
    """docs/walkers/steer_simbicon_six_sources.json on 15 sources at bearings -60..60 deg and 6, 10, 14 m (none a
    training source): median final distance at most 1.5 m (documented: 0.48 m; it falls on arrival)."""
    import numpy as np

    from evobiped.tasks.steer import with_sources

    genome, cfg, _ = load_genome(WALKERS / "steer_simbicon_six_sources.json")
    sources = [[3, -5.196], [5.196, -3], [6, 0], [5.196, 3], [3, 5.196], [5, -8.66], [8.66, -5], [10, 0], [8.66, 5], [5, 8.66],
               [7, -12.124], [12.124, -7], [14, 0], [12.124, 7], [7, 12.124]]  # as in docs/steering.md
    rows = with_sources(cfg, sources).build().run(genome).rows
    distances = np.linalg.norm(rows.end_position - np.array(sources), axis=1)
    assert np.median(distances) <= 1.5 and np.median(distances) == pytest.approx(0.48, abs=0.01)
