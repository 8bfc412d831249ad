"""The documentation a newcomer follows agrees with the tool: generated tables, docstrings, shipped walkers,
commands."""

from __future__ import annotations

import json
import math
import re
import shlex
import tomllib
from pathlib import Path

import pytest

from evobiped import readme

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


@pytest.mark.parametrize("page, ids", [
    (readme.USAGE, ["progress", "bodies", "controllers", "tasks", "terms", "optimizers", "presets"]),
    (readme.GYM, ["environments", "observations"]),
])
def test_generated_parts_agree_with_the_code(page, ids):
    """Regenerate with ``python -m evobiped.readme``."""
    text = page.read_text()
    assert readme.parts(text) == ids
    assert readme.render(text) == text, f"{page.name} is out of date: run python -m evobiped.readme"


def test_every_preset_is_in_the_presets_table():
    from evobiped.files.presets import names

    table = readme.generated()["presets"]
    assert [line.split("`")[1] for line in table.splitlines()[2:]] == names()


def test_every_sensor_an_observation_can_hold_is_described():
    from evobiped.bodies import BODIES
    from evobiped.tasks import TASKS

    for body in BODIES.values():  # what every sensor reads, declared beside its width
        assert set(body.sensor_widths) == set(body.sensor_text), body.name
    for task in TASKS.values():
        assert set(task().sensor_widths()) <= set(task.sensor_text), task.name


@pytest.mark.parametrize("name", ["ReilBipedEnv", "TagaBipedEnv", "ReilBipedVectorEnv", "TagaBipedVectorEnv"])
def test_the_environment_docstrings_give_the_observation_the_environment_returns(name):
    import numpy as np

    pytest.importorskip("gymnasium")
    from evobiped.envs import biped

    cls = getattr(biped, name)
    shape = re.search(r"Observation ``\((\d+),\)``", cls.__doc__)
    assert shape, cls.__doc__
    size = sum(readme.observation(cls.body_name).values())
    assert int(shape[1]) == size
    for part in readme.observation(cls.body_name):  # every part is named where the docstring lists them
        assert f"``{part}``" in cls.__doc__, part
    if name == "ReilBipedEnv":
        env = cls(seconds=0.1)
        obs, _ = env.reset(seed=0)
        assert obs.shape == env.observation_space.shape == (size,) and np.isfinite(obs).all()
        env.close()


def shipped_walkers() -> list[Path]:
    return sorted(p for p in (ROOT / "docs" / "walkers").glob("*.json") if not p.stem.endswith("_robustness"))


@pytest.mark.parametrize("path", shipped_walkers(), ids=lambda p: p.stem)
def test_every_shipped_walker_records_its_outcome(path):
    """What `replay` checks on a machine whose numerical environment differs: without it, nothing would be."""
    from dataclasses import asdict

    from evobiped.files.genome_file import load_genome
    from evobiped.files.outcome import TOLERANCE

    outcome = json.loads(path.read_text()).get("outcome")
    assert isinstance(outcome, dict), f"{path.name} has no outcome: scripts/refresh_walkers.py --write {path}"
    _, cfg, _ = load_genome(path)  # the outcome's form checked as replay reads it
    episode = cfg.nominal().build()
    rows = outcome["rows"]
    assert len(rows) == episode.task.presentations  # one row per presentation of the nominal episode
    assert outcome["fell"] == any(r["fell"] for r in rows) and outcome["end_time"] == min(r["end_time"] for r in rows)
    for r in rows:
        assert 0 < r["end_time"] <= cfg.seconds and (r["fell"] or r["end_time"] == cfg.seconds), r
        assert r["distance"] >= 0 and (r["heading_deg"] is None or -180 <= r["heading_deg"] <= 180), r
        # starts near the origin
        assert r["distance"] == pytest.approx(math.dist([0.0, 0.0], r["end_position"]), abs=0.5), r
    assert outcome["tolerance"] == asdict(TOLERANCE)


def test_ci_cites_a_readme_section_that_exists():
    cited = re.findall(r'README\.md \("([^"]+)"\)', (ROOT / ".ci" / "run").read_text())
    assert cited
    headings = [h.strip() for h in re.findall(r"^#+ (.+)$", (ROOT / "README.md").read_text(), re.M)]
    for name in cited:
        assert name in headings, (name, headings)


def toml_blocks(text: str) -> list[str]:
    return re.findall(r"```toml\n(.*?)```", text, re.S)


def settings_of(block: str, before: dict | None) -> dict:
    """The settings a TOML block of the docs stands for.  Its first line may say where it goes: ``# in [TABLE]`` (a
    table's lines), ``# over PRESET`` (laid over a preset), ``# over the settings above`` (over the page's block
    before, ``before``); otherwise it is a whole settings file."""
    from evobiped.core.fileio import read_toml
    from evobiped.files.presets import merge, path, split_declarations

    table, first = tomllib.loads(block), block.splitlines()[0]
    if m := re.match(r"# in \[([\w.]+)\]", first):
        for key in reversed(m[1].split(".")):
            table = {key: table}
    elif m := re.match(r"# over (the settings above|[\w-]+)", first):
        base = before if m[1] == "the settings above" else split_declarations(m[1], read_toml(path(m[1])))[0]
        assert base is not None, f"{first}: no settings above"
        table = merge(base, table)
    return table


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_toml_block_in_the_docs_is_accepted_as_evobiped_reads_it(page, tmp_path):
    """A settings file shown in the docs can be pasted as it stands: an evolve settings file (or a distill one) that
    ``evolve --config`` (``distill --config``) accepts, every name declared and every value in range; a body
    declaration that declares the box biped's model as it stands."""
    import shutil

    from evobiped.bodies import body_class
    from evobiped.core.errors import UserError
    from evobiped.physics.models import model_path
    from evobiped.run import RunConfig

    before = None
    for block in toml_blocks(page.read_text()):
        table = settings_of(block, before)
        try:
            if "legs" in table:  # a body declaration: of the model beside a declaration of docs/ with this text
                # (docs/own_robot/), else of the box biped's model, beside a copy of it
                same = [f.with_suffix(".xml") for f in sorted(ROOT.glob("docs/**/*.toml"))
                        if "legs" in f.read_text() and f.read_text().strip() == block.strip()]
                shutil.copy(same[0] if same else model_path("box_biped"), tmp_path / "declared.xml")
                (tmp_path / "declared.toml").write_text(block)
                body_class(f"mjcf:{tmp_path / 'declared.xml'}")
                continue
            if "distill" in table:
                from evobiped.distill.settings import parse_options

                parse_options(table["distill"])
            else:
                RunConfig.from_dict(table)
        except UserError as exc:
            raise AssertionError(f"{page.name}: {exc}\n{block}") from None
        before = table


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_no_settings_file_is_given_as_a_one_line_comment(page):
    """``# low_noise.toml:  [distill]  target_noise = 0.005   pose_noise = 0.01`` is invalid TOML once pasted."""
    assert not re.search(r"^# \S+\.toml:\s+\[", page.read_text(), re.M)


def readme_commands() -> list[list[str]]:
    text = (ROOT / "README.md").read_text().replace("\\\n", " ")  # continued lines joined
    lines = [line.split("#")[0].strip() for block in re.findall(r"```bash\n(.*?)```", text, re.S)
             for line in block.splitlines()]
    return [shlex.split(line.replace(".venv/bin/", "")) for line in lines
            if line.startswith(".venv/bin/evobiped ") or line.startswith("evobiped ")]


def test_the_readme_commands_parse():
    from evobiped.cli import build_parser

    commands = readme_commands()
    assert any(c[:2] == ["evobiped", "replay"] for c in commands)
    parser = build_parser()
    for c in commands:
        parser.parse_args(c[1:])


def test_the_readme_opens_the_recording_its_replay_wrote():
    """The recording the "Watch it" `rerun` line opens is the one the replay that renders the video wrote."""
    from evobiped.cli import build_parser

    text = (ROOT / "README.md").read_text()
    opened = re.findall(r"rerun (\S+\.rrd)", text)
    assert opened
    replays = [build_parser().parse_args(c[1:]) for c in readme_commands() if c[1] == "replay"]
    video = [a for a in replays if a.video and not a.out]
    assert video, "a replay with --video and the default recording"
    for path in opened:
        run, name = Path(path).parent, Path(path).name
        assert any(Path(a.source) == run and name == "replay_best_video.rrd" for a in video), path
