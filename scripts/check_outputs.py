"""Record the outputs of a fixed set of small evobiped commands, or compare two recordings.

A refactoring must not change behaviour: record the outputs before it, record
them again after it, and compare.  Every file the commands write is compared
byte for byte after dropping what legitimately changes between runs (wall-clock
times, the lock file, Rerun recordings, which embed ids and times):

    python scripts/check_outputs.py record before/     # on the old code
    python scripts/check_outputs.py record after/      # on the new code
    python scripts/check_outputs.py compare before/ after/

Takes about two minutes on 2 cores.  Exit status 1 when anything differs.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent

#: name -> evobiped arguments; OUT is replaced by the command's own output folder
COMMANDS: dict[str, list[str]] = {
    "evolve_reil_ctrnn": ["evolve", "--generations", "3", "--population", "8", "--episode-seconds", "4", "--seed", "1",
                          "--workers", "2", "--out", "OUT"],
    "evolve_reil_ctrnn_cyclic": ["evolve", "--preset", "paper-cyclic", "--generations", "2", "--population", "6",
                                 "--episode-seconds", "3", "--seed", "2", "--workers", "1", "--out", "OUT"],
    "evolve_reil_simbicon_cma": ["evolve", "--preset", "walker-simbicon", "--generations", "3", "--population", "6",
                                 "--episode-seconds", "4", "--seed", "3", "--workers", "2", "--out", "OUT"],
    "evolve_reil_simbicon_robust": ["evolve", "--preset", "walker-simbicon-robust", "--generations", "2",
                                    "--population", "4",
                                    "--episode-seconds", "3", "--seed", "0", "--workers", "2", "--from",
                                    str(REPO / "docs/walkers/simbicon_cma_seed5.json"), "--out", "OUT"],
    "evolve_reil_ctrnn_senses": ["evolve", "--preset", "walker-ctrnn-senses", "--generations", "2", "--population", "6",
                                 "--episode-seconds", "3", "--seed", "4", "--workers", "2", "--out", "OUT"],
    "evolve_reil_simbicon_steer": ["evolve", "--controller", "simbicon", "--task", "steer", "--generations", "2",
                                   "--population", "4", "--episode-seconds", "3", "--seed", "5", "--workers", "2",
                                   "--out", "OUT"],
    "evolve_taga_matsuoka": ["evolve", "--body", "taga", "--controller", "matsuoka", "--generations", "2",
                             "--population", "4",
                             "--episode-seconds", "2", "--seed", "6", "--workers", "2", "--out", "OUT"],
    "evolve_reil_g3": ["evolve", "--controller", "g3", "--generations", "2", "--population", "4",
                       "--episode-seconds", "2", "--seed", "7", "--workers", "1", "--out", "OUT"],
    "replay_reil_ctrnn": ["replay", "RUNS/evolve_reil_ctrnn", "--out", "OUT/replay.rrd", "--figures", "OUT"],
    "replay_simbicon_steer": ["replay", "RUNS/evolve_reil_simbicon_steer", "--out", "OUT/replay.rrd", "--figures",
                              "OUT"],
    "episode_taga_matsuoka": ["episode", "--body", "taga", "--controller", "matsuoka", "--seconds", "2", "--seed", "3",
                              "--json"],
    "episode_reil_simbicon": ["episode", "--controller", "simbicon", "--seconds", "3", "--seed", "2", "--json"],
    "taga": ["taga", "--u0", "5.0", "6.0", "--seconds", "5", "--window", "3", "--json", "--save-genome",
             "OUT/taga.json"],
    "taga_slope": ["taga", "--u0", "5.5", "--seconds", "4", "--window", "2", "--slope", "2", "--json"],
    "g3": ["g3", "human", "--sweep", "0.2", "1.0", "0.4", "--t-run", "40", "--json", "--out", "OUT"],
    "study": ["study", "--runs", "2", "--conditions", "plain,cyclic", "--generations", "2", "--population", "4",
              "--episode-seconds", "3", "--recheck-seconds", "4", "--workers", "2", "--out", "OUT", "--quiet"],
    "robustness": ["robustness", "RUNS/evolve_reil_simbicon_cma", "--seconds", "3", "--push-after", "1", "--out", "OUT",
                   "--json"],
    "evolve_reil_es_linear": ["evolve", "--preset", "walker-es-linear", "--generations", "3", "--seed", "1",
                              "--workers", "2", "--out", "OUT"],
    "evolve_reil_es_robust": ["evolve", "--preset", "walker-es-robust", "--from", "ctrnn_es_seed5.json",
                              "--generations", "2", "--seed", "2", "--workers", "2", "--out", "OUT"],
    "evolve_reil_steer_es": ["evolve", "--preset", "steer-es", "--from", "steer_ctrnn_es_seed0.json", "--generations",
                             "2", "--episode-seconds", "4", "--seed", "3", "--workers", "2", "--out", "OUT"],
    "replay_ctrnn_es": ["replay", "ctrnn_es_seed5.json", "--seconds", "3", "--out", "OUT/replay.rrd", "--figures",
                        "OUT"],
    "robustness_es": ["robustness", "ctrnn_es_robust_seed0.json", "--seconds", "3", "--push-after", "1", "--phase-seed",
                      "2", "--out", "OUT", "--json"],
}
#: shipped genome files copied into the recording's folder first (so every recording names them alike)
FILES = ("ctrnn_es_seed5.json", "ctrnn_es_robust_seed0.json", "steer_ctrnn_es_seed0.json")

#: file names never compared (volatile by nature)
SKIP_SUFFIXES = (".rrd", ".lock")
#: JSON keys and CSV columns holding wall-clock measurements
VOLATILE = ("wall", "elapsed", "seconds_taken", "started", "finished", "date")
#: JSON keys whose values differ between any two runs: pycma's timers, its logger, its tables of sent and injected
#: solutions (keyed by Python's per-process hashes), and where a start genome was read from (the recording's folder)
VOLATILE_KEYS = ("timer", "logger", "sent_solutions", "_injected_solutions_archive", "source_path")
#: where a history row (checkpoint.json's ``history``) holds its wall-clock seconds: history.csv's column 8
WALL_COLUMN = 8


def _volatile(key: str) -> bool:
    return any(v in key.lower() for v in VOLATILE)


def _strip(obj):
    if isinstance(obj, dict):
        if isinstance(obj.get("history"), list):  # a checkpoint's history rows hold the wall time
            obj = dict(obj, history=[row[:WALL_COLUMN] + row[WALL_COLUMN + 1:] for row in obj["history"]])
        return {k: _strip(v) for k, v in obj.items() if not _volatile(k) and k not in VOLATILE_KEYS}
    if isinstance(obj, list):
        return [_strip(v) for v in obj]
    return obj


#: a checkpoint's key of its format, absent from the checkpoints of before the format was written
CHECKPOINT_FORMAT = ("checkpoint.json", "format")


def normalised(path: Path) -> bytes:
    """The file's bytes with wall-clock fields removed (JSON keys, CSV columns), and checkpoint.json's format."""
    data = path.read_bytes()
    if path.suffix == ".json":
        try:
            obj = json.loads(data)
            if path.name == CHECKPOINT_FORMAT[0] and isinstance(obj, dict):
                obj.pop(CHECKPOINT_FORMAT[1], None)
            return json.dumps(_strip(obj), sort_keys=True).encode()
        except ValueError:
            return data
    if path.suffix == ".csv":
        rows = list(csv.reader(io.StringIO(data.decode())))
        if rows:
            keep = [i for i, h in enumerate(rows[0]) if not _volatile(h)]
            out = io.StringIO()
            csv.writer(out).writerows([[r[i] for i in keep if i < len(r)] for r in rows])
            return out.getvalue().encode()
    return data


def record(root: Path) -> int:
    root = root.resolve()
    root.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]))
    for name in FILES:
        (root / name).write_bytes((REPO / "docs" / "walkers" / name).read_bytes())
    for name, args in COMMANDS.items():
        out = Path("runs") / name  # relative to root: paths printed or drawn are the same in every recording
        (root / "runs").mkdir(exist_ok=True)
        if "OUT/" in " ".join(args) or args[0] in ("g3", "robustness", "replay"):
            (root / out).mkdir(parents=True, exist_ok=True)
        argv = [a.replace("OUT", str(out)).replace("RUNS", "runs") for a in args]
        proc = subprocess.run([sys.executable, "-m", "evobiped", *argv], capture_output=True, text=True, cwd=root,
                              env=env)
        (root / f"{name}.stdout").write_text(proc.stdout if "--json" in args else "")
        (root / f"{name}.rc").write_text(f"{proc.returncode}\n")
        print(f"{name}: exit {proc.returncode}", flush=True)
        if proc.returncode:
            print(proc.stderr[-2000:], file=sys.stderr)
    return 0


def digests(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(normalised(p)).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file() and not p.name.endswith(SKIP_SUFFIXES)}


def compare(a: Path, b: Path) -> int:
    da, db = digests(a), digests(b)
    bad = 0
    for name in sorted(set(da) | set(db)):
        if name not in da or name not in db:
            print(f"only in {'the first' if name in da else 'the second'}: {name}")
            bad += 1
        elif da[name] != db[name]:
            print(f"differs: {name}")
            bad += 1
    print(f"{len(set(da) & set(db))} files compared, {bad} differences")
    return 1 if bad else 0


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "record":
        sys.exit(record(Path(sys.argv[2])))
    if len(sys.argv) == 4 and sys.argv[1] == "compare":
        sys.exit(compare(Path(sys.argv[2]), Path(sys.argv[3])))
    sys.exit(__doc__)
