"""``evobiped genome``: the start genomes presets depend on, written by one command; bad input is one line, exit
status 2 and nothing written.  (tests/test_steer_es.py checks hearing-start and rewire walk as they should,
tests/test_es_robust.py ranges.)"""

import numpy as np
import pytest

from evobiped.files.genome_file import load_genome
from evobiped.files.presets import path as preset_path
from evobiped.core.fileio import read_toml
from evobiped.episode.remap import input_widths

from .conftest import WALKERS, cli

WALK = WALKERS / "ctrnn_walk_seed1.json"


def _columns(cfg) -> dict[str, slice]:
    """Input name -> its columns among the controller's inputs."""
    out, at = {}, 0
    for name, w in zip(cfg.parts()[1].input_names, input_widths(cfg)):
        out[name], at = slice(at, at + w), at + w
    return out


def test_command_start_adds_the_command_senses_at_zero_weight_and_keeps_every_other_gene(tmp_path, capsys):
    out = tmp_path / "start.json"
    assert cli("genome", "command-start", out, "--walker", WALK) == 0
    assert capsys.readouterr().out == f"{out}\n"
    g, cfg, meta = load_genome(out)
    old_g, old, _ = load_genome(WALK)
    assert meta["source"] == str(WALK)
    assert cfg.controller_options.inputs == read_toml(preset_path("walker-command-tune"))["episode"][
        "controller_options"]["inputs"]
    c, c_old = cfg.build().controller, old.build().controller
    columns, old_columns = _columns(cfg), _columns(old)
    assert set(columns) - set(old_columns) == {"command_speed", "command_turning", "command_stop"}
    s, s_old = c.layout.slices(), c_old.layout.slices()
    for block in ("input_weights", "direct_weights"):
        rows, rows_old = g[s[block]].reshape(c.n_inputs, -1), old_g[s_old[block]].reshape(c_old.n_inputs, -1)
        for name, at in columns.items():
            want = rows_old[old_columns[name]] if name in old_columns else np.zeros_like(rows[at])
            assert np.array_equal(rows[at], want) and (name in old_columns or not want.any()), name
    for block in ("weights", "biases", "time_constants", "direct_biases"):
        assert np.array_equal(g[s[block]], old_g[s_old[block]]), block
    assert sorted(p.name for p in tmp_path.iterdir()) == ["start.json"]


@pytest.mark.parametrize("args, words", [
    (["ranges", "ctrnn_es_robust_seed0.json", "--block", "weights", "a", "b"], "low and high must be numbers"),
    (["ranges", "ctrnn_es_robust_seed0.json", "--block", "nope", "-1", "1"], "no gene block 'nope'"),
    (["ranges", "ctrnn_es_robust_seed0.json", "--block", "weights", "2", "-2"], "is empty"),
    (["hearing-start", "--walker", "ctrnn_walk_seed1.json", "--reference-distance", "0"],
     "--reference-distance: must be > 0"),
    (["hearing-start", "--walker", "steer_ctrnn_es_seed0.json"], "does not read heading_error"),
    (["hearing-start", "--walker", "ctrnn_walk_preset_seed1.json"], "integrated by 'exponential', --preset steer-es's "
                                                                    "by 'euler' (take --preset steer-walk)"),
    (["hearing-start", "--walker", "ctrnn_walk_preset_seed1.json", "--preset", "walker-ctrnn"],
     "must be a steering preset of a network that hears"),
    (["rewire", "--walker", "ctrnn_es_seed5.json", "--drop", "loudness"], "does not read loudness"),
    (["rewire", "--walker", "ctrnn_es_seed5.json", "--add", "joint_angles"], "already reads joint_angles"),
    (["command-start", "--walker", "steer_simbicon_seed0.json"], "a simbicon genome cannot become a ctrnn genome"),
    (["rewire"], "the default docs/walkers/ctrnn_es_seed5.json is a path from the repository's root"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, args, words):
    action, *rest = args
    rest = [str(WALKERS / a) if a.endswith(".json") else a for a in rest]
    out = tmp_path / "out.json"
    argv = [action, *rest[:1], out, *rest[1:]] if action == "ranges" else [action, out, *rest]
    assert cli("genome", *argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("evobiped: error: ") and words in err, err
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("action", ["ranges", "hearing-start", "rewire", "command-start"])
def test_each_action_has_help(capsys, action):
    assert cli("genome", action, "--help") == 0
    text = capsys.readouterr().out
    assert text.startswith(f"usage: evobiped genome {action} ") and "OUT" in text
