"""The run directory's file names and paths (what each file holds: :mod:`evobiped.files.rundir`)."""

from __future__ import annotations

from pathlib import Path

from ...core.fileio import WriteError

CONFIG = "config.json"
START = "start.json"
CHECKPOINT = "checkpoint.json"
HISTORY = "history.csv"
BEST = "best.json"
SUMMARY = "summary.json"
RECORDING = "evolution.rrd"
GENERATIONS = "generations"
LOCK = ".lock"
#: a study's result for the run (evobiped study), with the long re-check
OUTCOME = "outcome.json"


def generation_file(directory: Path, generation: int) -> Path:
    """``DIR/generations/gen_NNNN.json``: the best genome of generation ``generation``."""
    return Path(directory) / GENERATIONS / f"gen_{generation:04d}.json"


def generation_files(directory: Path) -> list[Path]:
    """The generation files present, in file-name order."""
    return sorted((Path(directory) / GENERATIONS).glob("gen_*.json"))


def generation_of(path: Path) -> int | None:
    """The generation a ``gen_NNNN.json`` file holds (None: not such a name)."""
    digits = Path(path).stem[4:]
    return int(digits) if Path(path).stem.startswith("gen_") and digits.isdigit() else None


def label(genome_path: Path) -> str:
    """``best`` / ``gen_0007``: how replay and robustness name what they write about a run's genome file."""
    return Path(genome_path).stem


def replay_file(directory: Path, label: str) -> Path:
    """The default recording of a replay: ``DIR/replay_<label>.rrd``."""
    return Path(directory) / f"replay_{label}.rrd"


def figures_dir(directory: Path, label: str) -> Path:
    """The default folder of a replay's figures: ``DIR/figures_<label>``."""
    return Path(directory) / f"figures_{label}"


#: where replay and robustness write about a lone genome file when no --out is given, relative to the current
#: directory (never beside the file, which may sit in a repository)
GENOME_OUTPUTS = Path("runs")


def genome_outputs(genome_path: Path) -> Path:
    """The default folder for what replay and robustness write about a lone genome file: ``runs/<stem>``."""
    return GENOME_OUTPUTS / Path(genome_path).stem


def robustness_stem(label: str) -> str:
    """File stem of the robustness battery's results in a run directory: ``robustness`` for the best,
    ``robustness_<label>``."""
    return "robustness" if label == "best" else f"robustness_{label}"


def remove_stale_temporaries(directory: Path) -> list[Path]:
    """Delete the ``.NAME.*.tmp`` files a killed :func:`~evobiped.core.fileio.atomic_write` left; returns them."""
    found = [p for d in (Path(directory), Path(directory) / GENERATIONS) if d.is_dir() for p in d.glob(".*.tmp")]
    for p in found:
        p.unlink(missing_ok=True)
    return found


def is_unused(directory: Path) -> bool:
    """True for a directory that holds no run: nothing, or only what a run killed before writing its config leaves
    (the lock, an empty generations folder, temporaries, the start genome); a directory that cannot be listed is a
    WriteError."""
    try:
        configured = (Path(directory) / CONFIG).exists()
        for p in Path(directory).iterdir():
            temporary = p.name.startswith(".") and p.name.endswith(".tmp")
            start = p.name == START and not configured
            if not (p.name == LOCK or temporary or start
                    or (p.name == GENERATIONS and p.is_dir() and not any(p.iterdir()))):
                return False
    except OSError as exc:
        raise WriteError(exc.filename or directory, exc) from None
    return True

