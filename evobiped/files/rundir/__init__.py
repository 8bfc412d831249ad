"""The run-directory format in one place: file names (:mod:`.layout`), history.csv (:mod:`.history_file`), the
record of every individual (:mod:`.individuals_file`), the lock (:mod:`.locking`), the run's record
(checkpoint.json: :mod:`.record`), and which genome "a run directory or a genome file" names (:mod:`.genome_source`).

A run directory (``evobiped evolve --out DIR``)::

    start.json             the start genome (genome-file format, ``source``: where it came from), for a run started
    --from config.json            the full resolved RunConfig
    checkpoint.json        the commit point, the run's record (:mod:`.record`): its format, optimizer state,
                           history, best genome, outcomes after the last generation
    history.csv            one row per generation (HISTORY_COLUMNS)           } derived from the checkpoint,
    best.json              best genome of the run so far                      } rebuilt by a resume when
    evolution.rrd          fitness per generation, a Rerun recording          } missing, stale or damaged
    summary.json           written when the run ends: the best walker, its distance and walking direction
    generations/gen_NNNN.json   best genome of each generation (genome-file format), written just before its commit
    individuals.jsonl      every individual of every generation, one line each (generation, row, previous row, parents,
                           fitness, fell, unstable, end time, terms; unknown: null), appended just before each commit
    .lock                  held (flock) by the one process that evolves the run

Other commands add to it: ``outcome.json`` (a study's result for the run),
``replay_<label>.rrd`` and ``figures_<label>/`` (replay), ``robustness[_<label>].json/.png``
(the robustness battery), where the label is ``best`` or ``gen_NNNN``.

``start.json`` is written before config.json when the run is created: a resume
never reads ``--from`` again (the run may be resumed from any directory, its
source gone).  The checkpoint holds the start genome too, and the settings the
run was created with (``settings``: config.json's, less where episodes run),
so a resume refuses an edited config.json by name (:mod:`evobiped.run.fingerprint`).

``checkpoint.json`` is the run's one commit point per generation and its one
source of truth: ``history.csv``, ``best.json``, ``summary.json`` and
``evolution.rrd`` are derived from it and rebuilt from it on ``--resume``
whenever they are missing, stale or damaged.  ``generations/gen_NNNN.json``
is written just before the commit of generation NNNN (a resume deletes those
beyond the last commit); the checkpoint keeps each one's digest, and resume, replay and select check every
committed one against it (:mod:`.generation_check`).

The run directory owns the writers of its derived files: :func:`sync_file` (:mod:`.derived_file`) brings each to the
text the checkpoint gives it (history.csv, best.json, archive.json from what a MAP-Elites optimizer gives,
:mod:`.archive_file`), :mod:`.summary_file` writes summary.json; evolution.rrd is written by a listener of the run
(the recording's, :mod:`evobiped.record.recordings.evolution_log`) that the evolve use case attaches.

``individuals.jsonl`` is appended before the commit of its generation and cut
back to the committed generations' lines by a resume: no row of a committed
generation is duplicated or lost (:mod:`.individuals_file`).
"""

from .archive_file import ARCHIVE, ArchiveContents, archive_text
from .generation_check import check_generation_files, digest
from .record import (DIGESTS_KEY, FORMAT, FORMAT_KEY, OPTIMIZER_KEY, SETTINGS_KEY, START_KEY, RunRecord, check_start,
                     upgrade)
from .genome_source import FROM_CHECKPOINT, GenomeSource, check_at_rest, checkpoint_mark, genome_path, resolve_genome
from .individuals_file import (INDIVIDUALS, append_individuals, committed_size, cut_individuals, individuals_text,
                               read_individuals)
from .history_file import (HISTORY_COLUMNS, TERM_PREFIX, column, history_columns, history_text, read_history,
                           write_history)
from .layout import (BEST, CHECKPOINT, CONFIG, GENERATIONS, GENOME_OUTPUTS, HISTORY, LOCK, OUTCOME, RECORDING, START,
                     SUMMARY,
                     figures_dir, generation_file, generation_files, generation_of, genome_outputs, is_unused, label,
                     remove_stale_temporaries, replay_file, robustness_stem)
from .locking import lock, unlock
from .derived_file import sync_file
from .summary_file import agreeing_summary, summary_table, write_summary_file

__all__ = [
    "ARCHIVE", "ArchiveContents", "archive_text", "agreeing_summary", "summary_table", "sync_file",
    "write_summary_file", "BEST", "CHECKPOINT", "CONFIG", "DIGESTS_KEY", "check_generation_files", "digest",
    "GENERATIONS", "GENOME_OUTPUTS", "GenomeSource", "HISTORY", "HISTORY_COLUMNS",
    "INDIVIDUALS", "LOCK", "FORMAT", "FORMAT_KEY", "OPTIMIZER_KEY", "RunRecord", "check_start", "upgrade",
    "OUTCOME", "RECORDING", "SETTINGS_KEY", "START",
    "START_KEY", "SUMMARY", "TERM_PREFIX", "append_individuals", "column", "committed_size", "cut_individuals",
    "figures_dir", "generation_file", "generation_files", "generation_of", "genome_outputs", "genome_path",
    "history_columns", "history_text", "individuals_text", "is_unused", "label", "lock",
    "read_history", "read_individuals", "remove_stale_temporaries", "replay_file", "resolve_genome",
    "robustness_stem", "unlock", "write_history", "FROM_CHECKPOINT", "check_at_rest",
    "checkpoint_mark",
]
