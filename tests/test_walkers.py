"""The walkers shipped in docs/walkers behave as docs/walkers.md says, on any machine.

These tests assert behaviour (stays up, walks forward, reaches its sources, survives the battery's trials within
one per family), never a stored fitness: the last bits of a 50 s walk depend on the numerical environment
(evobiped.core.provenance), and the files were stored in one environment.  Bit-identity is tested between runs made on
the machine running the tests (tests/test_evolve.py, tests/test_replay.py), and here in a subprocess whose numpy
uses the other family of SIMD kernels.
"""

import dataclasses
import json
import re

import numpy as np
import pytest

from evobiped.files.genome_file import load_genome
from evobiped.core.options import given
from evobiped.analysis.robustness import battery, summarise

from .conftest import ROOT, WALKERS

#: a forward walker (docs/walkers.md): no fall in 200 s, at least 20 m in its first 50 s, within 30 deg of the
#: direction it faced at the start
FORWARD_WALKERS = ["simbicon_cma_seed5", "simbicon_cma_seed3", "simbicon_robust_curriculum_seed0_g66", "ctrnn_es_seed5"]


@pytest.mark.parametrize("name", FORWARD_WALKERS)
def test_a_forward_walker_walks_forwards_and_stays_up_200_s(name):
    genome, cfg, meta = load_genome(WALKERS / f"{name}.json")
    first = dataclasses.replace(cfg.nominal(), seconds=50.0).build().run(genome)  # whatever episode it evolved on
    walk = first.walk()
    assert not first.fell[0] and first.end_time[0] == 50.0
    assert walk["distance"] >= 20.0 and abs(walk["heading_deg"]) <= 30.0
    long = dataclasses.replace(cfg.nominal(), seconds=200.0).build().run(genome)
    assert not long.fell[0] and long.end_time[0] == 200.0


@pytest.mark.parametrize("name", sorted(p.stem.removesuffix("_robustness") for p in WALKERS.glob("*_robustness.json")))
def test_a_shipped_walker_still_reaches_its_documented_battery_figures(name):
    documented = json.loads((WALKERS / f"{name}_robustness.json").read_text())
    # <walker>_phasesN: pushes at random phases
    genome, cfg, _ = load_genome(WALKERS / f"{re.sub(r'_phases[0-9]+$', '', name)}.json")
    rows = summarise(battery(cfg.nominal().build(), genome, seconds=documented["seconds"],
                             push_after=documented["push_after"],
                                     phase_seed=documented.get("phase_seed")))
    got = {r["family"]: r["survived"] for r in rows}
    want = {r["family"]: r["survived"] for r in documented["families"]}
    assert got.keys() == want.keys()
    assert all(abs(got[f] - want[f]) <= 1 for f in want), (got, want)  # one trial per family may tip across machines


def test_a_forward_fitness_walker_replays_with_its_fitness_so_far(tmp_path, capsys):
    """The recording reads the forward fitness every tick: a walker still up counts as up to the end, so 2 s into its
    50 s episode its fitness so far is (forward + 5 m) x 1, not x 2/50 (nor 0)."""
    from evobiped.cli import main

    genome, cfg, _ = load_genome(WALKERS / "simbicon_cma_seed5.json")
    ep = cfg.nominal().build()
    state = ep.start(genome)
    ep.advance(state, 2.0)
    forward = float(ep.task.forward(state.task)[0])
    assert forward > 0.5 and ep.task.fitness(state.task)[0] == pytest.approx(forward + 5.0)
    assert main(["replay", str(WALKERS / "simbicon_cma_seed5.json"), "--seconds", "2", "--out", str(tmp_path / "r.rrd"),
                 "--quiet"]) == 0
    assert (tmp_path / "r.rrd").stat().st_size > 0


def test_the_shipped_steering_walker_reaches_both_paper_sources_without_falling():
    """docs/walkers/steer_simbicon_seed0.json: within 1.0 m of (10, 3) and of (10, -3) m after 50 s, up all the way."""
    import numpy as np

    genome, cfg, meta = load_genome(WALKERS / "steer_simbicon_seed0.json")
    assert cfg.task == "steer" and "sources" not in given(cfg.task_options)  # the paper's two sources, the default
    r = cfg.build().run(genome)
    rows = r.rows
    assert not rows.fell.any() and np.all(rows.end_time == 50.0)
    distances = np.linalg.norm(rows.end_position - np.array([[10.0, 3.0], [10.0, -3.0]]), axis=1)
    assert np.all(distances < 1.0)
    assert r.fitness[0] == pytest.approx(-distances.mean())


def test_the_six_source_steering_walker_reaches_sources_it_never_heard():
    """docs/walkers/steer_simbicon_six_sources.json on 15 sources at bearings -60..60 deg and 6, 10, 14 m (none a
    training source): median final distance at most 1.5 m (documented: 0.48 m on the machine that made the files;
    it falls on arrival)."""
    import numpy as np

    from evobiped.tasks.sound import with_sources

    genome, cfg, _ = load_genome(WALKERS / "steer_simbicon_six_sources.json")
    sources = [[3, -5.196], [5.196, -3], [6, 0], [5.196, 3], [3, 5.196], [5, -8.66], [8.66, -5], [10, 0], [8.66, 5],
               [5, 8.66], [7, -12.124], [12.124, -7], [14, 0], [12.124, 7], [7, 12.124]]  # as in docs/steering.md
    rows = with_sources(cfg, sources).build().run(genome).rows
    distances = np.linalg.norm(rows.end_position - np.array(sources), axis=1)
    assert np.median(distances) <= 1.5


def test_the_generalist_steering_walker_reaches_a_source_it_never_heard_and_stays_up():
    """docs/walkers/steer_generalist_seed0.json towards (5.196, -3) m (6 m at -30 deg, not a training source):
    within 1.0 m of it at 20 s and still up at 50 s (documented: 0.43 m at 20 s, up 50 s)."""
    import numpy as np

    from evobiped.tasks.sound import with_sources

    genome, cfg, _ = load_genome(WALKERS / "steer_generalist_seed0.json")
    assert cfg.task_options.fitness == "arrive" and cfg.controller_options.sound_limit == 0.1
    episode = with_sources(cfg, [[5.196, -3.0]]).build()
    early = episode.run(genome, seconds=20.0)
    assert not early.fell[0] and np.linalg.norm(early.end_position[0] - [5.196, -3.0]) < 1.0
    whole = episode.run(genome)
    assert not whole.fell[0] and whole.end_time[0] == 50.0


@pytest.mark.parametrize("disable", ["", "X86_V4 AVX512_ICL"])
def test_a_shipped_walker_replays_under_either_family_of_numpy_kernels(disable, tmp_path):
    """`evobiped replay` in a subprocess with numpy's AVX-512 kernels allowed and disabled: bit for bit where the
    subprocess's numerical environment is the recorded one, the same outcome within tolerance where it is not;
    exit 0 either way (on a CPU without AVX-512 both runs are the recorded environment)."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "NPY_DISABLE_CPU_FEATURES": disable, "PYTHONPATH": str(ROOT)}
    walker = WALKERS / "steer_simbicon_seed0.json"
    probe = "import json, evobiped.core.provenance as p; print(json.dumps(p.current()))"
    here = json.loads(subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True,
                                     check=True).stdout)
    _, _, meta = load_genome(walker)
    from evobiped.core.provenance import differences

    same = not differences(meta["environment"], here)
    run = subprocess.run([sys.executable, "-m", "evobiped", "replay", str(walker), "--quiet", "--out",
                          str(tmp_path / "r.rrd")],
                         env=env, capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    if same:
        assert "equals it bit for bit (same numerical environment)" in run.stdout
    else:
        assert "numerical environment differs" in run.stdout and "outcome holds" in run.stdout


@pytest.mark.parametrize("name, least, widest", [("ctrnn_distilled_seed5", 25.0, 35.0),
                                                 ("ctrnn_distilled_seed3", 12.0, 30.0),
                                                ("ctrnn_tuned_seed1", 20.0, 30.0)])
def test_a_distilled_ctrnn_walks_200_s_with_the_network_alone(name, least, widest):
    """A 40-neuron CTRNN sets every joint target (no balance law, no latency in the loop): no fall in 200 s, at
    least ``least`` m in its first 50 s within ``widest`` deg of its facing (documented: seed 5 31.4 m at +28.2 deg,
    a forward walker; seed 3 14.6 m at +16.2 deg; the tuned seed-1 student 24.7 m at +15.1 deg, a forward walker;
    the margins allow another numerical environment's drift)."""
    genome, cfg, _ = load_genome(WALKERS / f"{name}.json")
    cfg = cfg.nominal()  # a tuned walker's file keeps the perturbations it was tuned under
    assert cfg.controller == "ctrnn" and cfg.controller_options.n_neurons == 40
    assert cfg.latency == 0
    first = cfg.build().run(genome)
    walk = first.walk()
    assert not first.fell[0] and walk["distance"] >= least and abs(walk["heading_deg"]) <= widest
    long = dataclasses.replace(cfg, seconds=200.0).build().run(genome)
    assert not long.fell[0] and long.end_time[0] == 200.0


@pytest.mark.parametrize("name, failed, shuffles", [("ctrnn_walk_preset_seed1", [], True),
                                                    ("ctrnn_walk_seed1", ["slide_per_m"], True),
                                                    ("ctrnn_walk_robust_seed0", ["slip_share"], True),
                                                    ("ctrnn_stride_seed0", [], False)])
def test_the_shipped_from_scratch_walkers_gaits_are_their_docs_rows(name, failed, shuffles):
    """docs/walkers/ctrnn_walk_preset_seed1.json (--preset walker-ctrnn-walk as shipped, seed 1) walks by every
    criterion read at every physics step (up 200 s; duty factor >= 0.5 each foot, no flight, symmetric, stance slip
    <= 5 % of a speed >= 0.3 m/s and <= 10 cm slid per metre, on its line over the first 50 s); its uncapped-clearance
    version ctrnn_walk_seed1.json fails the tail bound alone, the robust walker the median slip alone; the quick
    start's walker fine-tuned by walker-walk-stride walks with steps of at least a quarter metre at under 3 a second,
    no shuffle; each row in docs/walkers.md's gait table holds within rounding and the tolerance of another numerical
    environment."""
    from evobiped.analysis.gait_report import gait_report

    genome, cfg, _ = load_genome(WALKERS / f"{name}.json")
    r = gait_report(cfg, genome, seconds=50.0, up_for=200.0)
    assert r["failed"] == failed and r["walks"] == (not failed)
    assert r["up"] and r["speed"] >= 0.3 and abs(r["heading_deg"]) <= 30
    assert min(r["duty_left"], r["duty_right"]) >= 0.5 and r["airborne"] <= 0.02 and r["duty_asymmetry"] <= 0.05
    assert r["shuffle"] == shuffles and (r["step_similar"] < 1 / 3) == shuffles
    if not shuffles:
        assert r["step_length"] >= 0.25 and r["steps_per_s"] <= 3.0 and r["cost_of_transport"] <= 0.6
    _is_its_docs_row(name, r, failed)


def _is_its_docs_row(name, r, failed):
    """docs/walkers.md's gait-table row of ``name`` holds gait report ``r`` (failing ``failed``) within rounding and
    the tolerance of another numerical environment."""
    lines = (ROOT / "docs" / "walkers.md").read_text().splitlines()
    head = [c.strip() for c in next(x for x in lines if x.startswith("| walker | up |")).strip("|").split("|")]
    row = next(line for line in lines if line.startswith(f"| `{name}`"))
    cells = dict(zip(head, (c.strip() for c in row.strip("|").split("|"))))
    assert cells["up"] == "200 s up" and cells["walks?"] == ("yes" if not failed else "no: " + ", ".join(failed))
    assert float(cells["speed (m/s)"]) == pytest.approx(r["speed"], abs=0.02)
    assert [float(x) for x in cells["duty L / R"].split("/")] == pytest.approx([r["duty_left"], r["duty_right"]],
                                                                               abs=0.02)
    assert float(cells["step (m)"]) == pytest.approx(r["step_length"], abs=0.02)
    assert float(cells["CoT"]) == pytest.approx(r["cost_of_transport"], abs=0.1)
    assert float(cells["slid (cm/m)"]) == pytest.approx(100 * r["slide_per_m"], abs=1.0)


def test_the_shipped_rhythm_generator_walker_walks_without_a_shuffle_and_its_rhythm_carries_it():
    """docs/walkers/matsuoka_walk_seed4.json (--preset walker-matsuoka-walk, seed 4): Matsuoka's oscillators with
    the body's senses fed back walk by every criterion (200 s up, duty >= 0.5 each foot, no flight, slip <= 5 %),
    with steps of at least a third of what dynamic similarity predicts (no shuffle) at under 4 a second; with the
    oscillators' outputs silenced (p_e = p_f = 0: the reflex and posture alone) the same genome falls."""
    from evobiped.analysis.gait_report import gait_report

    genome, cfg, _ = load_genome(WALKERS / "matsuoka_walk_seed4.json")
    assert cfg.controller == "matsuoka"
    r = gait_report(cfg, genome, seconds=50.0, up_for=200.0)
    assert r["walks"] and r["failed"] == [] and not r["shuffle"]
    assert r["step_length"] >= 0.18 and r["steps_per_s"] <= 4.0 and r["cost_of_transport"] <= 0.6
    _is_its_docs_row("matsuoka_walk_seed4", r, [])
    layout = cfg.build().controller.layout
    silent = np.array(genome, float).reshape(-1).copy()
    for block in ("p_e", "p_f"):
        silent[layout.slices()[block]] = 0.0
    assert not gait_report(cfg, silent, seconds=50.0, up_for=200.0)["up"]


def test_the_shipped_g3_preset_walker_walks_with_long_steps_by_its_reflex():
    """docs/walkers/g3_walk_seed2.json (--preset walker-g3-walk, seed 2) walks by every criterion with steps of 25
    cm at 2.5 a second (over half the step dynamic similarity predicts); as docs/rhythm_walkers.md says, its walk is
    the reflex's: with the G3 channels' outputs silenced (gain = 0) it still walks, without the reflex it falls."""
    from evobiped.analysis.gait_report import gait_report

    genome, cfg, _ = load_genome(WALKERS / "g3_walk_seed2.json")
    assert cfg.controller == "g3"
    r = gait_report(cfg, genome, seconds=50.0, up_for=200.0)
    assert r["walks"] and not r["shuffle"] and r["step_length"] >= 0.24 and r["steps_per_s"] <= 2.7
    _is_its_docs_row("g3_walk_seed2", r, [])
    slices = cfg.build().controller.layout.slices()
    for block, walks in (("gain", True), ("reflex_gain", False)):
        g = np.array(genome, float).reshape(-1).copy()
        g[slices[block]] = 0.0
        assert gait_report(cfg, g, seconds=50.0)["walks"] == walks, block
