"""A derived file of the run directory brought to the text the checkpoint gives it: the one way history.csv,
best.json, archive.json and the like are written at a commit and rebuilt by a resume."""

from __future__ import annotations

from pathlib import Path

from ...core.fileio import atomic_write


def sync_file(directory: Path, name: str, text: str | None, repairs: list[str] | None = None) -> None:
    """Give file ``name`` of ``directory`` the content ``text`` (None: no such file) unless it has it, atomically.
    ``repairs`` (a resume's list; None: a commit) gets one sentence when the file had to change."""
    path = directory / name
    try:
        current = path.read_text() if path.exists() else None
    except (OSError, UnicodeDecodeError):
        current = ""
    if current == text:
        return
    if repairs is not None:
        repairs.append(
            f"{name} {'rewritten from the checkpoint' if text is not None else 'removed (no generation is complete)'}")
    if text is None:
        path.unlink(missing_ok=True)
    else:
        atomic_write(path, text)
