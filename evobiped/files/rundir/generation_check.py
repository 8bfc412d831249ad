"""The committed generation files checked against the checkpoint: each ``generations/gen_NNNN.json`` of a committed
generation must be the file that generation committed.

The checkpoint records each one's digest (``generation_digests``: the SHA-256 of its text; null, for a generation
committed before they were kept: the file's generation and fitness against the history).  A file that is missing,
cut, edited or
swapped for another is rewritten when the checkpoint holds its genome (the run's best generation: best.json, itself
derived from the checkpoint), and otherwise refused with one line naming it: no command goes on with another genome
than the one the run committed under that generation's name.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from ...core.errors import UserError
from ...core.fileio import atomic_write, read_json
from .layout import BEST, CHECKPOINT, GENERATIONS, generation_file
from .record import DIGESTS_KEY, FORMAT, check_digests, upgrade


def digest(text: str) -> str:
    """The digest the checkpoint keeps of a generation file's text."""
    return hashlib.sha256(text.encode()).hexdigest()


def _text(path: Path) -> str | None:
    try:
        return path.read_text()
    except (OSError, UnicodeDecodeError):
        return None


def _holds(text: str | None, g: int, ck: dict, *, genome: bool = False) -> bool:
    """``text`` is generation ``g``'s file as far as the checkpoint can tell: its digest, else its generation and
    fitness (and, for a candidate replacement, the checkpoint's best genome)."""
    if text is None:
        return False
    digests = ck[DIGESTS_KEY]
    if g < len(digests) and digests[g] is not None and digest(text) == digests[g]:
        return True
    if g < len(digests) and digests[g] is not None and not genome:
        return False
    import json

    try:
        obj = json.loads(text)
    except ValueError:
        return False
    if not isinstance(obj, dict) or obj.get("generation") != g or not isinstance(obj.get("genome"), list):
        return False
    row = ck["history"][g]
    if obj.get("fitness") != row[1]:  # the history's best of generation g
        return False
    return not genome or obj["genome"] == ck.get("best_genome")


def check_generation_files(directory: str | Path, ck: dict | None = None) -> list[str]:
    """Check every committed generation file of the run in ``directory`` against its checkpoint (``ck``: already
    read, in the current format; None: read it, of any format, none there: nothing is committed).  Rewrites a
    damaged one from best.json where that is
    the generation's best, and returns what it rewrote (one sentence each); UserError naming the first file that
    cannot be."""
    d = Path(directory)
    if ck is None:
        if not (d / CHECKPOINT).is_file():
            return []
        ck = upgrade(read_json(d / CHECKPOINT, what="checkpoint", file_format=FORMAT), d)
    if not isinstance(ck, dict) or not isinstance(ck.get("history"), list):
        raise UserError(f"checkpoint {d / CHECKPOINT} is not a checkpoint")
    check_digests(ck)
    best = ck.get("best") if isinstance(ck.get("best"), dict) else {}
    repairs = []
    for g in range(len(ck["history"])):
        path = generation_file(d, g)
        if _holds(_text(path), g, ck):
            continue
        missing = not path.exists()
        what = "is missing" if missing else "is not the file its generation committed (cut, edited or replaced)"
        name = f"{GENERATIONS}/{path.name}"
        if best.get("generation") == g:
            text = _text(d / BEST)
            if _holds(text, g, ck, genome=True):
                atomic_write(path, text)
                repairs.append(f"{name} rewritten from the checkpoint (it was "
                               f"{'missing' if missing else 'cut, edited or replaced'})")
                continue
        raise UserError(f"{d / name} {what}, and the checkpoint does not hold that generation's best genome: "
                        f"restore the file from a copy of the run")
    return repairs

