"""The open-loop controller (scripts/open_loop_probe.py's gaits): its two forms on the bodies, and a probe's genome
replays."""

import runpy
import sys
from pathlib import Path

import numpy as np
import pytest

from evobiped.episode import EpisodeConfig
from evobiped.core.errors import ConfigError
from evobiped.files.genome_file import load_genome
from evobiped.core.options import given

from .conftest import cli

PROBE = Path(__file__).resolve().parent.parent / "scripts" / "open_loop_probe.py"


def sine_genome(lay, **genes):
    """A sine-form genome: every gene at its range's middle, then ``genes`` set (units of open_loop.SINE_RANGES)."""
    g = 0.5 * (lay.low + lay.high)
    for k, v in genes.items():
        g[lay.names().index(f"{k}[0]")] = v
    return g


def test_sine_form_targets_and_episode_on_the_reil_body():
    ep = EpisodeConfig(controller="open-loop", seconds=1.0).build()
    ctrl, lay = ep.controller, ep.controller.layout
    assert lay.size == 9 and ctrl.output_kind == "angle" and ctrl.input_names == ()
    g = sine_genome(lay, frequency=1.0, hip_amplitude=0.4, hip_offset=0.1, knee_amplitude=0.5, knee_offset=-0.3,
                    knee_phase=0.0, roll_amplitude=0.0, roll_offset=0.05)
    p = ctrl.decode(g)
    # a quarter period in: the left hip at offset + amplitude, the right (half a period behind) at offset - amplitude;
    # left knee min(0, -0.3 + 0.5) = 0, right knee -0.8; actuators: left hip pitch, hip roll, knee, then the right's
    out = ctrl.neuron_outputs(p, np.array([0.25]))[0]
    assert out == pytest.approx([0.5, 0.05, 0.0, -0.3, 0.05, -0.8])
    # neutral targets (no rhythm, straight legs) stand: no fall, the pelvis stays put
    still = sine_genome(lay, hip_amplitude=0.0, hip_offset=0.0, knee_amplitude=0.0, knee_offset=0.0, roll_amplitude=0.0,
                        roll_offset=0.0)
    r = ep.run(np.stack([still, g]))
    assert not r.fell[0] and r.end_time[0] == 1.0 and abs(r.fitness[0]) < 0.02
    assert np.isfinite(r.fitness).all() and abs(r.fitness[1]) > 0.05  # the rhythm moves the walker


def test_fourier_form_drives_any_body_and_the_sine_form_is_refused_on_the_taga_body():
    ep = EpisodeConfig(body="taga", controller="open-loop", controller_options={"form": "fourier"}, seconds=0.5).build()
    assert ep.controller.layout.size == 1 + 5 * 6 and ep.controller.output_kind == "unit"
    r = ep.run(ep.controller.layout.sample(np.random.default_rng(0), 2))
    assert np.isfinite(r.fitness).all() and (r.end_time > 0).all()
    with pytest.raises(ConfigError, match="needs a left and a right leg with the joints hip_pitch, hip_roll, knee"):
        EpisodeConfig(body="taga", controller="open-loop").layout()


def test_a_probe_genome_saved_by_the_script_replays_to_its_fitness(tmp_path, monkeypatch, capsys):
    out = tmp_path / "best.json"
    monkeypatch.setattr(sys, "argv", ["open_loop_probe.py", "--search", "cma", "--family", "sine", "--rounds", "3",
                                      "--population", "4", "--seconds", "1", "--seed", "2", "--save", str(out)])
    runpy.run_path(str(PROBE), run_name="__main__")
    genome, cfg, meta = load_genome(out)
    assert cfg.controller == "open-loop" and given(cfg.controller_options) == {"form": "sine"} and len(genome) == 9
    assert meta["search"] == "cma" and 0 < meta["end_time"] <= 1.0
    assert cfg.build().run(genome).fitness[0] == meta["fitness"]
    pytest.importorskip("rerun")
    capsys.readouterr()
    assert cli("replay", out, "--out", tmp_path / "r.rrd", "--quiet") == 0
    assert "the replay equals it bit for bit" in capsys.readouterr().out
