"""Fault campaign on ``evobiped evolve`` (and the commands that read its files), for a release check.

Twenty-seven classes of faults.  Nine strike at random moments and are repeated ``--repeat`` times (50 or more for a
release): a pool worker SIGKILLed, every worker killed, SIGTERM/SIGHUP to a worker, the resource tracker then a
worker, every worker killed 2 to 6 pools in a row, the whole run SIGKILLed, SIGINT/SIGTERM/SIGHUP to the run,
SIGINT at any moment from a command's start (evolve, replay, select, ``-h``; or to the process group while workers
start), and a replay or select killed between its outputs.  The others are fixed cases: tampered checkpoints, edited
configs, hostile settings files, genome files, ``select`` on damaged runs, runs started ``--from`` a relative path,
damaged generation files, worker counts beyond the machine per backend, an empty value for every flag, and a run
directory whose name is not UTF-8; and the newer commands' numbers, environment (``MUJOCO_GL``, ``ulimit -n``), paths
that are no file, a run being written, ``gait``'s outputs killed between them, the experiments'
outputs (``g3 --out``, ``g3 --reproduce``, ``taga --reproduce``) killed between them, and ``ulimit -v``.  The classes
after the first fourteen run their commands under a memory guard (a quarter of the machine, at most 8 GiB of address
space) and check every case for residue: temporaries, a set's mark, a video's temporary folder, processes that outlived
their command.

Each case ends in one verdict: ``identical`` (the run completed and equals an undisturbed one file for file, wall
times aside), ``resumed`` (it stopped, with one line where it could say one, and ``--resume`` completed it, equal
to an undisturbed one), ``refused, resumed`` (the workers died past the retries: one line, exit status 2, then
the same), ``refused`` (one line on stderr, exit status 2, and nothing of the run directory changed where that is
asked), or a failure: ``traceback``, ``hang`` (no answer within the
time limit), ``silent`` (accepted and wrong: exit 0 where a refusal is due, or a completed run that differs),
``stale`` (a read of a run being written accepted without saying so), ``residue`` (a file left
behind), ``orphan`` (a process that outlived its command), ``mixed`` (a new output beside an old one of the same
command) and ``other``.  The exit status is 1 when any case fails.

    python scripts/fault_campaign.py --repeat 50 --out /tmp/campaign      # about an hour on 2 cores
    python scripts/fault_campaign.py --repeat 2 --classes worker-sigkill group-kill

Runs are tiny (8 walkers, 6 generations, 2 s episodes); everything is written under ``--out``.  The fixed cases'
damage and the words of their refusals are tests/fault_cases.py's, which the fault tests run too; a refusal that does
not say them is ``other``.  ``scripts/fault_campaign.py`` runs this module; tests/test_faults_workers.py runs three
random-moment classes once (:func:`campaign`).
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from collections import Counter, defaultdict
from pathlib import Path

from .fault_cases import (CHECKPOINT_EDITS, CONFIG_EDITS, DEEP, DIFFERS, GENOME_EDITS, NUMBERS, SELECT_DAMAGE, SETTINGS,
                          edit, number_case)
from .test_faults import children, contents, files  # the fault tests' process tree, run contents and file snapshots

ROOT = Path(__file__).resolve().parents[1]
RUN = ["--population", "8", "--generations", "6", "--episode-seconds", "2", "--seed", "5", "--quiet"]
PROCESS = [*RUN, "--backend", "process", "--workers", "2"]
LIMIT = 180.0  # s: a case that takes longer hangs
#: the last stderr line of each command run (``--show`` prints the fixed cases' answers)
ANSWERS: list[str] = []
#: the whole stderr of each command and run (a failed case's are kept beside its run directory)
STDERR: list[str] = []
FAILURES = ("traceback", "hang", "silent", "stale", "other", "residue", "orphan", "mixed")


# ---- running the command
def guard() -> None:
    """A child's memory guard: at most :data:`MEMORY` bytes of address space, so a case never threatens the machine."""
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY, MEMORY))


#: the address space a guarded case's process may take (bytes): a quarter of the machine, at most 8 GiB
MEMORY = min(8 * 2**30, os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") // 4)
#: processes a command left in its process group after it ended (killed, then counted as residue)
LEFTOVER: list[str] = []


def command(*args, cwd=None, env=None, timeout=LIMIT, guarded=False) -> tuple[int | None, str, str]:
    """``evobiped ARGS`` in a child process (``guarded``: under the memory guard): (exit status, None on a hang;
    stderr; stdout).  Processes left in its process group afterwards are killed and noted in :data:`LEFTOVER`."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), **(env or {})}
    p = subprocess.Popen([sys.executable, "-m", "evobiped", *map(str, args)], cwd=cwd, env=env, text=True,
                         errors="replace",
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True, preexec_fn=guard
                             if guarded else None)
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
        return None, err, out
    _leftovers(p.pid, " ".join(map(str, args[:2])))
    ANSWERS.append((err.strip().splitlines() or [""])[-1])
    STDERR.append(err)
    return p.returncode, err, out


def _group(pgid: int) -> list[int]:
    """The live processes (zombies aside: ended, not yet reaped by init) of process group ``pgid``."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":
            found.append(int(stat.parent.name))
    return found


def _leftovers(pgid: int, what: str) -> None:
    """Kill and note the processes of a command's group that outlive it by more than 1.5 s (a worker's own watch
    ends it within 0.5 s of its parent)."""
    deadline = time.time() + 1.5
    while _group(pgid) and time.time() < deadline:
        time.sleep(0.1)
    left = _group(pgid)
    if left:
        for pid in left:
            kill(pid)
        LEFTOVER.append(f"{what}: {len(left)} processes outlived it")


def start(d: Path) -> subprocess.Popen:
    def defaults():  # as a terminal delivers them, even where this runs under nohup
        for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            signal.signal(s, signal.SIG_DFL)
        os.setpgrp()

    return subprocess.Popen([sys.executable, "-m", "evobiped", "evolve", *PROCESS, "--out", str(d)], text=True,
                            stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env={**os.environ, "PYTHONPATH": str(ROOT)}, preexec_fn=defaults)


def is_tracker(pid: int) -> bool:
    try:
        return b"resource_tracker" in Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return False


def workers(pid: int) -> list[int]:
    return [k for k in children(pid) if not is_tracker(k)]


#: what the random-moment trials of the current class did: trials that killed or signalled a live process
#: (``struck``), that printed a retry (``retried``), that ended past the retries (``past the retries``)
STRUCK: Counter = Counter()


def kill(pid: int, sig=signal.SIGKILL) -> bool:
    try:
        os.kill(pid, sig)
    except ProcessLookupError:
        return False
    return True


def first_commit(p: subprocess.Popen, d: Path) -> None:
    deadline = time.time() + LIMIT
    while not (d / "checkpoint.json").exists() and p.poll() is None and time.time() < deadline:
        time.sleep(0.002)


def last_commit(p: subprocess.Popen, d: Path, generations: int = 6) -> None:
    deadline = time.time() + LIMIT
    while p.poll() is None and time.time() < deadline:
        try:
            if len(json.loads((d / "checkpoint.json").read_text())["history"]) >= generations:
                return
        except (OSError, ValueError, KeyError):
            pass
        time.sleep(0.002)


def finish(p: subprocess.Popen) -> tuple[int | None, str]:
    try:
        _, err = p.communicate(timeout=LIMIT)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        _, err = p.communicate()
        return None, err
    STDERR.append(err)
    return p.returncode, err


# ---- verdicts
#: a note a run prints as it goes on, not an error
RETRY_NOTE = "evobiped: a worker died; evaluating its batch again"


def one_line(err: str) -> bool:
    """One line of error (beside the notes of retries before it), no traceback."""
    lines = [x for x in err.splitlines() if not x.startswith(RETRY_NOTE)]
    return len(lines) == 1 and err.endswith("\n") and "Traceback" not in err


def verdict(rc, err: str, d: Path | None = None, reference: dict | None = None) -> str:
    """``identical`` (exit 0, equal to ``reference`` where given), ``refused`` (one line, exit 2), or a failure."""
    if rc is None:
        return "hang"
    if "Traceback" in err:
        return "traceback"
    if rc == 0:
        return "identical" if reference is None or contents(d) == reference else "silent"
    if rc == 2 and one_line(err):
        return "refused"
    return "other"


def resumed(d: Path, reference: dict, rc, err: str) -> str:
    """The verdict of a disturbed run (exit status ``rc``, stderr ``err``): then ``--resume`` until it completes (a
    one-line refusal before is fine when the resumed run equals the undisturbed one)."""
    if rc is None:
        return "hang"
    if "Traceback" in err:
        return "traceback"
    if rc not in (0, 2, -signal.SIGKILL, *(128 + s
                                           for s in (signal.SIGINT, signal.SIGTERM,
                                                     signal.SIGHUP))) or rc == 2 and not one_line(err):
        return "other"
    how = "identical" if rc == 0 else "refused, resumed" if rc == 2 else "resumed"
    for _ in range(3):
        if (d / "summary.json").exists() and contents(d) == reference:
            return how
        rc, err, _ = command("evolve", "--resume", d, "--quiet")
        v = verdict(rc, err)
        if v in ("hang", "traceback", "other"):
            return v
        how = how if how != "identical" else "resumed"
    return how if contents(d) == reference else "silent"


# ---- the random-moment classes
def _moment() -> float:
    return random.uniform(0.0, 0.6)


def worker_kill(d, reference, how: str) -> str:
    p = start(d)
    first_commit(p, d)
    time.sleep(_moment())
    ws = workers(p.pid)
    hit = False
    if how == "one" and ws:
        hit = kill(random.choice(ws))
    elif how == "all":
        hit = any([kill(w) for w in ws])
    elif how == "term" and ws:
        hit = kill(random.choice(ws), random.choice([signal.SIGTERM, signal.SIGHUP]))
    elif how == "tracker":
        for k in children(p.pid):
            if is_tracker(k):
                kill(k)
        time.sleep(random.uniform(0.0, 0.2))
        ws = workers(p.pid)
        if ws:
            hit = kill(random.choice(ws))
    elif how == "storm":
        for _ in range(random.randint(2, 6)):
            hit = any([kill(w) for w in workers(p.pid)]) or hit
            time.sleep(random.uniform(0.05, 0.3))
    rc, err = finish(p)
    STRUCK["struck"] += hit
    STRUCK["retried"] += RETRY_NOTE in err
    STRUCK["past the retries"] += "workers died" in err
    if rc == 2 and "workers died" not in err:
        return "other"
    return resumed(d, reference, rc, err)


def group_kill(d, reference) -> str:
    p = start(d)
    first_commit(p, d)
    time.sleep(_moment())
    os.killpg(p.pid, signal.SIGKILL)
    rc, err = finish(p)
    STRUCK["struck"] += rc == -signal.SIGKILL
    return resumed(d, reference, rc, err)


def late_signal(d, reference) -> str:
    p = start(d)
    first_commit(p, d)
    if random.random() < 0.5:  # any moment
        time.sleep(random.uniform(0.0, 1.0))
    else:  # within a tenth of a second of the final commit
        last_commit(p, d)
        time.sleep(random.uniform(0.0, 0.1))
    sig = random.choice([signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
    kill(p.pid, sig)
    rc, err = finish(p)
    STRUCK["struck"] += rc != 0
    if rc is None:
        return "hang"
    if "Traceback" in err:
        return "traceback"
    if rc == 0:  # finished before the signal came
        return "identical" if contents(d) == reference else "silent"
    if rc != 128 + sig or not one_line(err):
        return "other"
    complete = (d / "summary.json").exists() and contents(d) == reference
    says = "run completed" in err if complete else "--resume" in err
    if not says:
        return "silent"
    return "identical" if complete else resumed(d, reference, rc, err)


RANDOM = {
    "worker-sigkill": lambda d, ref: worker_kill(d, ref, "one"),
    "workers-all": lambda d, ref: worker_kill(d, ref, "all"),
    "worker-term-hup": lambda d, ref: worker_kill(d, ref, "term"),
    "tracker-then-worker": lambda d, ref: worker_kill(d, ref, "tracker"),
    "worker-storm": lambda d, ref: worker_kill(d, ref, "storm"),
    "group-kill": group_kill,
    "late-signal": late_signal,
}


# ---- the fixed classes
def refusal(rc, err: str, words: str) -> str:
    """The verdict of a case that must be refused with one line saying ``words``: ``refused``; exit 0 is ``silent``, a
    refusal that does not say them ``other``."""
    v = verdict(rc, err).replace("identical", "silent")
    return "other" if v == "refused" and words not in err else v


def _case(name: str, v: str) -> tuple[str, str, str]:
    """A fixed case's name, verdict and the last line its command printed (a residue: what it left)."""
    if v == "residue" and STDERR and STDERR[-1].startswith("residue: "):
        return name, v, STDERR[-1]
    return name, v, ANSWERS[-1] if ANSWERS else ""


def checkpoint_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    out = []
    for name, (change, words) in CHECKPOINT_EDITS.items():
        d = work / f"ck-{len(out)}"
        shutil.copytree(done, d)
        edit(d / "checkpoint.json", change)
        before = files(d)
        rc, err, _ = command("evolve", "--resume", d)
        v = refusal(rc, err, words)
        out.append(_case(name, "silent" if v == "refused" and files(d) != before else v))
    d = work / "ck-deep"
    shutil.copytree(done, d)
    (d / "checkpoint.json").write_text(DEEP)
    rc, err, _ = command("evolve", "--resume", d)
    out.append(_case("100,000-deep checkpoint", refusal(rc, err, "nested more than 32 deep")))
    return out


def cma_cases(work: Path) -> list[tuple[str, str]]:
    """An older CMA-ES checkpoint claiming 20,000 told generations; a CMA-ES strategy tampered with."""
    d = work / "cma"
    rc, err, _ = command("evolve", *RUN, "--optimizer", "cma", "--backend", "serial", "--out", d)
    if rc != 0:
        return [_case("cma run", verdict(rc, err))]
    out = []
    cases = {
        "20,000 told generations": lambda ck: {**ck, "settings": ck["settings"],
                                               "optimizer": {"name": "cma", "generation": 20000,
                                                "told": [[0.0] * len(ck["optimizer"]["fitness"])] * 20000,
                                                             "fitness": ck["optimizer"]["fitness"]}},
        "strategy names os.system": lambda ck: {**ck,
                                                "optimizer": json.loads(json.dumps(ck["optimizer"]).replace(
                                                    '"cma.sampler:', '"os:', 1))},
        "strategy arrays cut": lambda ck: {**ck,
                                           "optimizer": json.loads(json.dumps(ck["optimizer"]).replace(
                                               '"b64": "', '"b64": "AAAA', 1))},
    }
    for name, change in cases.items():
        c = work / f"cma-{len(out)}"
        shutil.copytree(d, c)
        edit(c / "checkpoint.json", change)
        rc, err, _ = command("evolve", "--resume", c, timeout=60)
        out.append(_case(name, verdict(rc, err).replace("identical", "silent")))
    return out


def config_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    out = []
    original = json.loads((done / "config.json").read_text())
    for name, (change, words) in CONFIG_EDITS.items():
        d = work / f"cfg-{len(out)}"
        shutil.copytree(done, d)
        (d / "summary.json").unlink()  # a run cut before its end
        edit(d / "config.json", change)
        rc, err, _ = command("evolve", "--resume", d)
        v = refusal(rc, err, words(original))
        out.append(_case(f"config.json {name} edited", "other" if v == "refused" and DIFFERS not in err else v))
    return out


def settings_cases(work: Path) -> list[tuple[str, str]]:
    out = []
    for name, (text, words) in SETTINGS.items():
        f = work / f"s{len(out)}.toml"
        f.write_text(text + "\n")
        d = work / f"s{len(out)}"
        population = [] if "population" in name else ["--population", "4"]
        rc, err, _ = command("evolve", "--config", f, "--episode-seconds", "1", *population, "--backend", "thread",
                             "--workers", "2", "--out", d, "--quiet")
        out.append(_case(name, "silent" if d.exists() else refusal(rc, err, words)))
    rc, err, _ = command("evolve", "--preset", "walker-ctrnn-distilled", "--out", work / "preset", "--quiet",
                         timeout=60)
    out.append(_case("preset needing --from without it", "silent" if (work / "preset").exists()
                     else refusal(rc, err, "--from")))
    return out


def genome_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    good = json.loads((done / "best.json").read_text())
    out = []
    for name, (change, words) in GENOME_EDITS.items():
        f = work / f"g{len(out)}.json"
        f.write_text(json.dumps(change(good)))
        rc, err, _ = command("replay", f, "--out", work / f"g{len(out)}.rrd", "--quiet")
        out.append(_case(f"replay: {name}", refusal(rc, err, words)))
    f = work / "deep.json"
    f.write_text(DEEP)
    rc, err, _ = command("replay", f, "--quiet")
    out.append(_case("replay: 100,000-deep genome file", refusal(rc, err, "nested more than 32 deep")))
    return out


def select_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    out = []
    for name, (damage, words) in SELECT_DAMAGE.items():
        d = work / f"sel-{len(out)}"
        shutil.copytree(done, d)
        damage(d)
        rc, err, _ = command("select", d, "--top", "8", "--seconds", "1")
        out.append(_case(f"select: {name}", refusal(rc, err, words)))
    return out


def start_cases(work: Path) -> list[tuple[str, str]]:
    """A run started --from a relative path, resumed from another directory (cut, and complete), its source gone."""
    here = work / "from"
    here.mkdir()
    ref = work / "from-ref"
    rc, err, _ = command("evolve", *RUN, "--backend", "serial", "--out", ref)
    if rc != 0:
        return [_case("--from setup", verdict(rc, err))]
    shutil.copy(ref / "best.json", here / "seed.json")
    whole = here / "whole"
    rc, err, _ = command("evolve", *RUN, "--backend", "serial", "--from", "seed.json", "--out", "whole", cwd=here)
    if rc != 0:
        return [_case("--from run", verdict(rc, err))]
    reference = contents(whole)
    out = []
    for n in (4, 9, 14):  # cut before the first commit, in the middle, at the end
        d = here / f"cut{n}"
        command("evolve", *RUN, "--backend", "serial", "--from", "seed.json", "--out", d.name, cwd=here,
                env={"EVOBIPED_FAULT_KILL_AT_REPLACE": str(n)})
        elsewhere = work / f"elsewhere{n}"
        elsewhere.mkdir()
        (here / "seed.json").rename(here / "seed.moved")
        try:
            rc, err, _ = command("evolve", "--resume", d, "--quiet", cwd=elsewhere)
        finally:
            (here / "seed.moved").rename(here / "seed.json")
        out.append(_case(f"--from seed.json, cut at write {n}, resumed elsewhere", verdict(rc, err, d, reference)))
    rc, err, _ = command("evolve", "--resume", whole, cwd=work)
    out.append(_case("--from seed.json, complete, resumed elsewhere", verdict(rc, err)))
    return out


FIXED = {
    "checkpoint": checkpoint_cases,
    "cma-checkpoint": lambda work, done: cma_cases(work),
    "config-edit": config_cases,
    "settings-file": lambda work, done: settings_cases(work),
    "genome-file": genome_cases,
    "select": select_cases,
    "start-genome": lambda work, done: start_cases(work),
}


# ---- a hostile user's input (the classes after the fourteen above)
def residue(*dirs: Path) -> list[str]:
    """What a case must never leave: temporaries of a write cut short, a set's mark, a video's temporary folder in
    the system's, processes of its commands (:data:`LEFTOVER`)."""
    import tempfile

    found = [str(p) for d in dirs if Path(d).is_dir() for pat in (".*.tmp*", ".*.incomplete")
             for p in Path(d).rglob(pat)]
    found += [str(p) for p in Path(tempfile.gettempdir()).glob("tmp*/video.mp4")]
    return found


def _checked(v: str, *dirs: Path) -> str:
    """A verdict, unless the case left residue (what it left goes to the case's stderr, :data:`STDERR`)."""
    left, orphans = residue(*dirs), LEFTOVER[:]
    LEFTOVER.clear()
    if left or orphans:
        STDERR.append("residue: " + "; ".join(left + orphans))
    return v if v in FAILURES else "orphan" if orphans else "residue" if left else v


def _interpreters_own(err: str) -> bool:
    """A traceback of Python's own start (its site module, runpy finding evobiped) before any of evobiped's code."""
    frames = [x for x in err.splitlines() if x.strip().startswith("File ")]
    return bool(frames) and not any("evobiped" in f or "site-packages" in f for f in frames) and \
        any("<frozen site>" in f or "<frozen runpy>" in f for f in frames)


def start_signal(d: Path, reference) -> str:
    """SIGINT at a random moment 0.02-0.6 s from the start of evolve, replay, select or -h, or to the process group
    0.5-1.5 s into an evolve on two worker processes; then a stopped evolve resumed."""
    done = d.parent / "done"
    what = random.choice(["evolve", "replay", "select", "help", "group"])
    args = {"evolve": ["evolve", *RUN, "--backend", "serial", "--out", d], "help": ["evolve", "-h"],
            "replay": ["replay", done, "--seconds", "1", "--out", d / "r.rrd"],
            "select": ["select", done, "--seconds", "1"], "group": ["evolve", *PROCESS, "--out", d]}[what]
    d.mkdir(parents=True, exist_ok=True) if what in ("replay", "select") else None
    p = subprocess.Popen([sys.executable, "-m", "evobiped", *map(str, args)], text=True, errors="replace",
                         stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, env={**os.environ, "PYTHONPATH": str(ROOT)}, start_new_session=True)
    time.sleep(random.uniform(0.5, 1.5) if what == "group" else random.uniform(0.02, 0.6))
    if kill(p.pid, signal.SIGINT) if what != "group" else _killpg(p.pid, signal.SIGINT):
        STRUCK["signalled"] += 1
    try:
        _, err = p.communicate(timeout=LIMIT)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        return "hang"
    STDERR.append(f"{what} {' '.join(map(str, args))}:\n{err}")
    _leftovers(p.pid, what)
    if "Traceback" in err:
        if _interpreters_own(err):
            STRUCK["in Python's own start"] += 1
            return "python-start"
        return "traceback"
    lines = [x for x in err.splitlines() if not x.startswith(RETRY_NOTE)]
    # -SIGINT: before Python's handler, as a shell's 130
    if p.returncode not in (0, 130, -signal.SIGINT) or len(lines) > 1:
        return "other"
    if p.returncode in (130, -signal.SIGINT) and what in ("evolve", "group") and (d / "config.json").exists():
        rc, err, _ = command("evolve", "--resume", d, "--quiet")
        return _checked("resumed" if rc == 0 else verdict(rc, err), d, done)
    return _checked("completed" if p.returncode == 0 else "stopped", d, done)


def _killpg(pgid: int, sig) -> bool:
    try:
        os.killpg(pgid, sig)
    except ProcessLookupError:
        return False
    return True


def output_kill(d: Path, reference) -> str:
    """A replay (recording and figures) or a select killed at a random rename of its outputs, then run again: never a
    new file beside an old one of the same command, and the next run says the previous was cut short."""
    shutil.copytree(d.parent / "done", d)
    replay = random.random() < 0.5
    args = ["replay", d, "--seconds", "1", "--figures", "--quiet"] if replay else ["select", d, "--seconds", "1"]
    rc, err, _ = command(*args)
    if rc != 0:
        return verdict(rc, err)
    outputs = (lambda: [d / "replay_best.rrd", *(d / "figures_best").glob("*.png")]) if replay else \
        (lambda: [d / "selected.json", d / "selected_candidates.json"])
    time.sleep(0.05)
    t0 = time.time()
    rc, err, _ = command(*args, env={"EVOBIPED_FAULT_KILL_AT_REPLACE": str(random.randint(1, 9 if replay else 3))})
    if rc is None or "Traceback" in err:
        return verdict(rc, err)
    if rc == -signal.SIGKILL:
        STRUCK["killed between outputs"] += 1
        new = [p.stat().st_mtime >= t0 for p in outputs() if p.exists()]
        if any(new) and not all(new):
            return "mixed"
    cut = rc == -signal.SIGKILL and bool(list(d.glob(".*.incomplete")))
    rc, err, _ = command(*args)
    if rc != 0 or "Traceback" in err:
        return verdict(rc, err)
    if cut and "cut short" not in err:
        return "silent"
    return _checked("rewritten" if cut else "identical", d)


RANDOM.update({"start-signal": start_signal, "output-kill": output_kill})


def generation_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    """Committed generation files cut, deleted, swapped or edited, then --resume, replay and select: the best
    generation's is rewritten from the checkpoint, any other refused by name."""
    best = json.loads((done / "checkpoint.json").read_text())["best"]["generation"]
    other = next(g for g in range(6) if g != best)

    def gen(d, g):
        return d / "generations" / f"gen_{g:04d}.json"

    def edited(key, change):  # the file's ``key`` changed (``edit`` is tests.fault_cases')
        return lambda d, g: edit(gen(d, g), lambda obj: {**obj, key: change(obj[key])})

    damage = {
        "cut": lambda d, g: gen(d, g).write_bytes(gen(d, g).read_bytes()[:100]),
        "deleted": lambda d, g: gen(d, g).unlink(),
        "swapped": lambda d, g: shutil.copyfile(gen(d, (g + 1) % 6), gen(d, g)),
        "a gene edited": edited("genome", lambda x: [x[0] / 2 + 0.125, *x[1:]]),
        "fitness edited": edited("fitness", lambda f: f + 1.0),
    }
    out = []
    for name, harm in damage.items():
        for g in (best, other):
            for cmd in ("resume", "replay", "select"):
                d = work / f"gen-{len(out)}"
                shutil.copytree(done, d)
                harm(d, g)
                before = files(d)
                args = {"resume": ["evolve", "--resume", d],
                        "replay": ["replay", d, "--generation", g, "--seconds", "1"],
                        "select": ["select", d, "--seconds", "1"]}[cmd]
                rc, err, _ = command(*args)
                v = verdict(rc, err)
                if g == best:  # rewritten from the checkpoint, as committed
                    v = "rewritten" if rc == 0 and gen(d,
                                                       g).read_bytes() == gen(done,
                                                                              g).read_bytes() else v.replace(
                                                                                  "identical", "silent")
                else:  # refused by name, nothing changed
                    v = "silent" if v == "identical" or (v == "refused"
                                                         and (gen(d, g).name not in err or files(d) != before)) else v
                out.append(_case(f"gen_{g:04d}.json {name}, {cmd}", _checked(v, d)))
    return out


def worker_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    """Worker counts beyond the machine on every backend, as a flag and in a settings file, under the memory guard."""
    out = []
    for backend in ("thread", "process", "ray"):
        for n in ("100000", "1000000000"):
            d = work / f"workers-{len(out)}"
            rc, err, _ = command("evolve", *RUN, "--backend", backend, "--workers", n, "--out", d, guarded=True,
                                 timeout=60)
            out.append(_case(f"--backend {backend} --workers {n}",
                             _checked(verdict(rc, err).replace("identical", "silent"), d)))
        (work / "workers.toml").write_text("workers = 100000\n")
        d = work / f"workers-{len(out)}"
        rc, err, _ = command("evolve", *RUN, "--backend", backend, "--config", work / "workers.toml", "--out", d,
                             guarded=True, timeout=60)
        out.append(_case(f"--backend {backend}, workers = 100000 in a settings file",
                         _checked(verdict(rc, err).replace("identical", "silent"), d)))
    return out


def empty_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    """An empty value for every flag and argument of every command that takes one."""
    import argparse

    from evobiped.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    out = []
    for name, parser in sub.choices.items():
        for action in parser._actions:
            if action.nargs in (0, argparse.PARSER) or isinstance(action, argparse._SubParsersAction):
                continue
            n = action.nargs if isinstance(action.nargs, int) else 1
            args = [action.option_strings[0], *[""] * n] if action.option_strings else [""]
            cwd = work / f"empty-{len(out)}"
            cwd.mkdir()
            rc, err, _ = command(name, *args, cwd=cwd, guarded=True, timeout=60)
            v = verdict(rc, err).replace("identical", "silent")
            out.append(_case(f"{name} {' '.join(args) or 'POSITIONAL'}", _checked(v, cwd) if not any(cwd.iterdir())
                             or v != "refused" else "residue"))
    return out


def latin1_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    """A run directory whose name is not UTF-8 (byte 0xff), in a UTF-8 locale: evolve, resume, replay, select."""
    d = work / os.fsdecode(b"run\xff")
    env = {"LC_ALL": "C.UTF-8"}
    out = []
    for name, args in (("evolve --out", ["evolve", *RUN, "--backend", "serial", "--out", d]),
                       ("evolve --resume", ["evolve", "--resume", d]),
                       ("evolve --resume again", ["evolve", "--resume", d]),
                       ("replay --figures", ["replay", d, "--seconds", "1", "--figures"]),
                       ("select", ["select", d, "--seconds", "1"])):
        rc, err, _ = command(*args, env=env)
        v = verdict(rc, err)
        if name == "evolve --resume again" and "repaired" in err:
            v = "silent"  # a second resume has nothing to repair
        out.append(_case(f"{name} {d.name!a}", _checked(v, d)))
    return out


FIXED.update({"generation-file": generation_cases, "workers": worker_cases, "empty-string": empty_cases,
              "non-utf8": latin1_cases})


# ---- the newer commands: numbers, the environment, paths that are no file, a run being written, gait's outputs
def number_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    """Every number of :data:`tests.fault_cases.NUMBERS`, in an empty folder that must stay empty, under the guard."""
    out = []
    for name in NUMBERS:
        cwd = work / f"numbers-{len(out)}"
        (cwd / "tmp").mkdir(parents=True)
        args, words = number_case(name, ROOT, cwd / "tmp")
        rc, err, _ = command(*args, cwd=cwd, guarded=True, timeout=60)
        v = refusal(rc, err, words)
        written = [p.name for p in cwd.rglob("*") if p != cwd / "tmp"]
        out.append(_case(name, "residue" if v == "refused" and written else _checked(v, cwd)))
    return out


def _limited(args, files: int, cwd: Path) -> tuple[int | None, str]:
    """``evobiped ARGS`` with at most ``files`` open file descriptors (``ulimit -n``)."""
    import resource

    def few():
        resource.setrlimit(resource.RLIMIT_NOFILE, (files, resource.getrlimit(resource.RLIMIT_NOFILE)[1]))

    try:
        r = subprocess.run([sys.executable, "-m", "evobiped", *map(str, args)], cwd=cwd, capture_output=True, text=True,
                           timeout=LIMIT, env={**os.environ, "PYTHONPATH": str(ROOT)}, preexec_fn=few)
    except subprocess.TimeoutExpired:
        return None, ""
    ANSWERS.append((r.stderr.strip().splitlines() or [""])[-1])
    return r.returncode, r.stderr


def environment_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    """``MUJOCO_GL`` values MuJoCo's import stops at (commands that render nothing run; a video is one line), and too
    few file descriptors for a pool."""
    out = []
    walker = ROOT / "docs" / "walkers" / "ctrnn_walk_seed1.json"
    for value in ("bogus", "osmesa-x", "wgl", "EGL "):
        for name, args in (("presets", ["presets"]), ("episode", ["episode", "--genome", walker, "--seconds", "0.5"]),
                           ("replay", ["replay", walker, "--seconds", "0.5", "--out", "r.rrd"])):
            cwd = work / f"env-{len(out)}"
            cwd.mkdir()
            rc, err, _ = command(*args, cwd=cwd, env={"MUJOCO_GL": value}, guarded=True, timeout=120)
            out.append(_case(f"MUJOCO_GL={value!r} {name}",
                             _checked(verdict(rc, err).replace("refused", "silent"), cwd)))
        cwd = work / f"env-{len(out)}"
        cwd.mkdir()
        rc, err, _ = command("replay", walker, "--seconds", "0.5", "--video", "v.mp4", "--out", "r.rrd", cwd=cwd,
                             env={"MUJOCO_GL": value}, guarded=True, timeout=120)
        v = refusal(rc, err, "MUJOCO_GL") if value.strip().lower() != "egl" else verdict(rc, err)
        out.append(_case(f"MUJOCO_GL={value!r} replay --video", _checked(v, cwd)))
    for open_files in (12, 14):
        for backend in ("process", "thread"):
            cwd = work / f"env-{len(out)}"
            cwd.mkdir()
            rc, err = _limited(["evolve", *RUN, "--backend", backend, "--workers", "2", "--out", cwd / "run"],
                               open_files, cwd)
            v = "hang" if rc is None else refusal(rc, err, "too many open files") if rc != 0 else "identical"
            out.append(_case(f"ulimit -n {open_files}, evolve --backend {backend}", _checked(v, cwd)))
    return out


def odd_path_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    """A genome or run path that is a FIFO, a symbolic link loop, a broken link or a device, for every command that
    reads a stored walker: one line saying what it is."""
    out = []
    for kind, words in (("fifo", "is a FIFO"), ("loop", "symbolic link in a loop"), ("broken", "broken symbolic link"),
                        ("device", "is a character device")):
        for args in (["replay", "{p}", "--seconds", "0.5"], ["episode", "--genome", "{p}"], ["gait-report", "{p}"],
                     ["robustness", "{p}"], ["gait", "{p}", "--speed", "0.5"], ["distill", "{p}"],
                     ["genome", "command-calibrate", "{p}", "out.json"],
                     ["genome", "ranges", "{p}", "out.json", "--block", "weights", "-1", "1"]):
            cwd = work / f"odd-{len(out)}"
            cwd.mkdir()
            p = Path("/dev/null") if kind == "device" else cwd / kind
            if kind == "fifo":
                os.mkfifo(p)
            elif kind == "loop":
                p.symlink_to(p)
            elif kind == "broken":
                p.symlink_to(cwd / "gone.json")
            rc, err, _ = command(*[a.format(p=p) for a in args], cwd=cwd, guarded=True, timeout=60)
            v = refusal(rc, err, words)
            out.append(_case(f"{kind} to {args[0]}{' ' + args[1] if args[0] == 'genome' else ''}",
                             "residue" if v == "refused" and [x for x in cwd.iterdir() if x != p]
                                 else _checked(v, cwd)))
    return out


def _stale(v: str) -> str:
    """A read of a run being written (or gone past) accepted without saying so is a stale read."""
    return "stale" if v == "silent" else v


def live_run_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    """The commands that read a run, on one an evolve is writing: refused by name (or, ``--allow-unfinished``, the
    generation recorded); a selection made then, read once the run went on: refused, never reused silently."""
    d = work / "live"
    p = subprocess.Popen([sys.executable, "-m", "evobiped", "evolve", "--population", "4", "--generations", "300",
                          "--seconds",
                          "0.5", "--backend", "serial", "--quiet", "--out", str(d)],
                         env={**os.environ, "PYTHONPATH": str(ROOT)},
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    out = []
    try:
        deadline = time.time() + 120
        while not (d / "checkpoint.json").exists() and time.time() < deadline:
            time.sleep(0.05)
        words = f"is being written by process {p.pid}; wait or pass --allow-unfinished"
        for args in (["select", d, "--seconds", "1", "--top", "1"], ["replay", d, "--seconds", "0.5"],
                     ["replay", d / "best.json", "--seconds", "0.5"],
                     ["replay", d, "--generation", "0", "--seconds", "0.5"],
                     ["gait-report", d, "--seconds", "1"], ["robustness", d, "--seconds", "2", "--push-after", "1"],
                     ["distill", d, "--iterations", "1"]):
            rc, err, _ = command(*args, guarded=True, timeout=60)
            out.append(_case(f"{' '.join(map(str, args[:2]))} of a run being written", _stale(refusal(rc, err, words))))
        rc, err, _ = command("select", d, "--seconds", "1", "--top", "1", "--allow-unfinished", guarded=True)
        chosen = json.loads((d / "selected.json").read_text()).get("from_checkpoint") if rc == 0 else None
        v = verdict(rc, err) if rc != 0 else "identical" if chosen and chosen.get("writer") == p.pid else "silent"
        out.append(_case("select --allow-unfinished of a run being written", _stale(v)))
        for args in (["replay", d, "--seconds", "0.5", "--allow-unfinished"],
                     ["gait-report", d, "--seconds", "1", "--allow-unfinished"]):
            rc, err, _ = command(*args, guarded=True, timeout=60)
            v = verdict(rc, err) if rc != 0 else "identical" if "is being written by process" in err else "silent"
            out.append(_case(f"{args[0]} --allow-unfinished of a run being written", _stale(v)))
        while chosen and len(json.loads((d / "checkpoint.json").read_text())["history"]) == chosen["generations"]:
            time.sleep(0.1)
    finally:
        p.kill()
        p.communicate()
    for args in (["replay", d / "selected.json", "--seconds", "0.5"],
                 ["gait-report", d / "selected.json", "--seconds", "1"]):
        rc, err, _ = command(*args, guarded=True, timeout=60)
        out.append(_case(f"{args[0]} of a selection the run has gone past",
                         _stale(refusal(rc, err, "choose again with evobiped select"))))
    return out


def gait_output_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    """A commanded walker's gait (its JSON and figure one set) SIGKILLed at each rename of its outputs, then run
    again."""
    out = []
    walker = ROOT / "docs" / "walkers" / "ctrnn_command_seed1.json"
    args = ["gait", walker, "--speed", "0.5", "--hold", "3"]
    for n in (1, 2, 3):
        d = work / f"gait-{n}"
        rc, err, _ = command(*args, "--out", d, guarded=True)
        names = sorted(x.name for x in d.iterdir()) if d.is_dir() else []
        rc, err, _ = command(*args, "--out", d, env={"EVOBIPED_FAULT_KILL_AT_REPLACE": str(n)}, guarded=True)
        if rc != -signal.SIGKILL:
            out.append(_case(f"gait killed at rename {n}", verdict(rc, err)))
            continue
        if all((d / x).exists() for x in names):
            out.append(_case(f"gait killed at rename {n}", "mixed"))
            continue
        rc, err, _ = command(*args, "--out", d, guarded=True)
        v = verdict(rc, err)
        if v == "identical":  # cut short after its mark: said; at the mark's own write: nothing of it to say
            v = "rewritten" if "was cut short" in err else "identical" if n == 1 else "silent"
        v = v if sorted(x.name for x in d.iterdir()) == names else "residue"
        out.append(_case(f"gait killed at rename {n}, run again", _checked(v, d)))
    return out


FIXED.update({"numbers": number_cases, "environment": environment_cases, "odd-path": odd_path_cases,
              "live-run": live_run_cases, "gait-output": gait_output_cases})


# ---- the experiments' outputs as one set; too little address space
def _set_after_kill(args, d: Path, files, n: int, old: bytes | None = None) -> str:
    """``evobiped ARGS`` SIGKILLed at its ``n``-th rename over the previous set in ``d`` (``files`` where it stands,
    ``old`` their bytes where they were made by hand): ``mixed`` if a new file stands beside an old one, else the
    exit status' verdict ("" where it was killed)."""
    time.sleep(0.05)
    t0 = time.time()
    rc, err, _ = command(*args, env={"EVOBIPED_FAULT_KILL_AT_REPLACE": str(n)}, guarded=True)
    here = [f for f in files if f.exists()]
    new = [f.stat().st_mtime >= t0 and (old is None or f.read_bytes() != old) for f in here]
    if any(new) and not all(new):
        return "mixed"
    return "" if rc == -signal.SIGKILL else verdict(rc, err)


#: a G3 reproduction on a coarse grid (2 levels per sweep, 40 time units each: some 30 s)
G3_QUICK = ["--step", "0.25", "--t-run", "40"]


def reproduce_output_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    """``g3 --out``, ``g3 --reproduce`` and ``taga --reproduce`` SIGKILLed at renames of their outputs over a previous
    set (a real one, or every file of the set made by hand), then run again: never a new file beside an old one."""
    from evobiped.experiments.g3.g3_figures import sweep_files
    from evobiped.experiments.g3.g3_reproduce import g3_outputs
    from evobiped.experiments.taga.taga_reproduce import taga_outputs

    out, old = [], b"the previous run's"
    for n in (1, 2, 3):
        d = work / f"g3-out-{n}"
        command("g3", "fig4", "--out", d, guarded=True)  # one level: its run and its diagrams
        args = ["g3", "fig4", "--go", "0.1", "0.2", "--out", d]  # two: the diagrams and the frequency plot
        v = _set_after_kill(args, d, sweep_files(d, "g3_fig4"), n)
        if not v:
            rc, err, _ = command(*args, guarded=True)
            v = verdict(rc, err)
            if v == "identical":
                v = "rewritten" if "was cut short" in err else "identical" if n == 1 else "silent"
            if sorted(x.name for x in d.iterdir()) != ["g3_fig4_diagrams.png", "g3_fig4_frequency.png"]:
                v = "residue"
        out.append(_case(f"g3 --out killed at rename {n}, run again", _checked(v, d)))
    for what, args, outputs, kills in (
            ("g3 --reproduce", ["g3", "--reproduce", "{d}", *G3_QUICK], g3_outputs, (2, 9, 20, 30)),
            ("taga --reproduce", ["taga", "--reproduce", "{d}", "--quick", "--quiet"], taga_outputs, (2, 3))):
        for n in kills:
            d = work / f"{what.split()[0]}-reproduce-{n}"
            d.mkdir()
            for f in outputs(d):
                f.write_bytes(old)
            v = _set_after_kill([a.format(d=d) for a in args], d, outputs(d), n, old)
            if not v:  # the next run says the previous was cut short, before its own mark (killed there)
                rc, err, _ = command(*[a.format(d=d) for a in args], env={"EVOBIPED_FAULT_KILL_AT_REPLACE": "1"},
                                     guarded=True)
                v = "rewritten" if rc == -signal.SIGKILL and "was cut short" in err else verdict(rc, err)
                v = "silent" if v == "identical" else v
            out.append(_case(f"{what} killed at rename {n} over a previous set", v))
    d = work / "g3-reproduce-whole"  # a whole reproduction after one cut short: said, and only its set's files
    d.mkdir()
    command("g3", "--reproduce", d, *G3_QUICK, env={"EVOBIPED_FAULT_KILL_AT_REPLACE": "5"}, guarded=True)
    rc, err, _ = command("g3", "--reproduce", d, *G3_QUICK, guarded=True)
    v = verdict(rc, err)
    if v == "identical":
        v = "rewritten" if "was cut short" in err else "silent"
        v = v if {x.name for x in d.iterdir()} <= {f.name for f in g3_outputs(d)} else "residue"
    out.append(_case("g3 --reproduce whole after one cut short", _checked(v, d)))
    return out


def _address_space(args, kib: int, cwd: Path) -> tuple[int | None, str]:
    """``evobiped ARGS`` in ``cwd`` with at most ``kib`` KiB of address space (``ulimit -v``)."""
    import resource

    def little():
        resource.setrlimit(resource.RLIMIT_AS, (kib * 1024, kib * 1024))

    try:
        r = subprocess.run([sys.executable, "-m", "evobiped", *map(str, args)], cwd=cwd, capture_output=True, text=True,
                           timeout=LIMIT, env={**os.environ, "PYTHONPATH": str(ROOT)}, preexec_fn=little,
                           start_new_session=True)
    except subprocess.TimeoutExpired:
        return None, ""
    ANSWERS.append((r.stderr.strip().splitlines() or [""])[-1])
    return r.returncode, r.stderr


def memory_cases(work: Path, done: Path) -> list[tuple[str, str]]:
    """Every command under ``ulimit -v`` below the 512 MiB the command starts in (one line naming the limit, the
    minimum and the fix, nothing written), and at it and above: run, or one line naming the limit."""
    walker = ROOT / "docs" / "walkers" / "ctrnn_walk_seed1.json"
    commanded = ROOT / "docs" / "walkers" / "ctrnn_command_seed1.json"
    commands = {"presets": ["presets"], "episode": ["episode", "--genome", walker, "--seconds", "0.5"],
                "replay": ["replay", walker, "--seconds", "0.5", "--out", "r.rrd"], "taga": ["taga", "--seconds", "1"],
                "g3": ["g3", "fig4", "--out", "g3"],
                "evolve": ["evolve", *RUN, "--backend", "process", "--workers", "2", "--out", "run"],
                "gait": ["gait", commanded, "--speed", "0.5", "--hold", "1", "--out", "g"]}
    out = []
    for kib in (50_000, 200_000, 400_000, 524_287):
        for name, args in commands.items():
            cwd = work / f"memory-{len(out)}"
            cwd.mkdir()
            rc, err = _address_space(args, kib, cwd)
            v = "hang" if rc is None else refusal(rc, err, f"(ulimit -v {kib}), below the 524,288 KiB (512 MiB)")
            out.append(_case(f"ulimit -v {kib} {name}", "residue" if v == "refused" and any(cwd.iterdir()) else v))
    for kib in (524_288, 700_000):
        for name, args in commands.items():
            cwd = work / f"memory-{len(out)}"
            cwd.mkdir()
            rc, err = _address_space(args, kib, cwd)
            v = "hang" if rc is None else refusal(rc, err, f"(ulimit -v {kib})") if rc != 0 else verdict(rc, err)
            if name in ("presets", "episode") and kib == 524_288 and v == "refused":
                v = "other"  # the stated minimum runs them
            out.append(_case(f"ulimit -v {kib} {name}", v))
    return out


FIXED.update({"reproduce-output": reproduce_output_cases, "memory-limit": memory_cases})


def campaign(work: Path, classes: list[str], repeat: int, show: bool = False) -> tuple[dict[str, Counter], list[str]]:
    """Run ``classes`` (the random-moment ones ``repeat`` times each) in the emptied folder ``work``: each class's
    verdicts counted, and a note for each failed case (its commands' stderr kept beside its run directory)."""
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    ref_dir = work / "reference"
    rc, err, _ = command("evolve", *PROCESS, "--out", ref_dir)
    assert rc == 0, err
    reference = contents(ref_dir)
    done = work / "done"  # a completed serial run to damage (the fixed classes)
    if set(classes) & {*FIXED, "start-signal", "output-kill"}:
        rc, err, _ = command("evolve", *RUN, "--backend", "serial", "--out", done)
        assert rc == 0, err
    results: dict[str, Counter] = defaultdict(Counter)
    notes = []
    for name in classes:
        STRUCK.clear()
        if name in RANDOM:
            for i in range(repeat):
                d = work / f"{name}-{i}"
                STDERR.clear()
                v = RANDOM[name](d, reference)
                if LEFTOVER:  # processes of its commands that outlived them
                    STDERR.append("orphans: " + "; ".join(LEFTOVER))
                    v = v if v in FAILURES else "orphan"
                    LEFTOVER.clear()
                results[name][v] += 1
                if v in FAILURES:
                    notes.append(f"{name} #{i}: {v} ({d}; its commands' stderr in {d}.stderr)")
                    Path(f"{d}.stderr").write_text("\n----\n".join(STDERR))
                else:
                    shutil.rmtree(d, ignore_errors=True)
        else:
            for case, v, answer in FIXED[name](work, done):
                if show:
                    print(f"  {case}: {v}: {answer}")
                results[name][v] += 1
                if v in FAILURES:
                    notes.append(f"{name}: {case}: {v}: {answer}")
            if LEFTOVER:  # processes a case outlived that no verdict of its own counted
                results[name]["orphan"] += 1
                notes.append(f"{name}: orphan: {'; '.join(LEFTOVER)}")
                LEFTOVER.clear()
        struck = f"  ({', '.join(f'{k} {n}' for k, n in STRUCK.items())})" if name in RANDOM else ""
        print(f"{name:<22} {sum(results[name].values()):>4} cases  "
              + ", ".join(f"{k} {n}" for k, n in sorted(results[name].items())) + struck,
              flush=True)
    return results, notes


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=50, help="trials of each random-moment class (default 50)")
    ap.add_argument("--out", default="/tmp/evobiped-fault-campaign", help="working folder (emptied first)")
    ap.add_argument("--classes", nargs="*", help=f"only these: {', '.join([*RANDOM, *FIXED])}")
    ap.add_argument("--seed", type=int, default=0, help="seed of the random moments")
    ap.add_argument("--show", action="store_true", help="print each fixed case's verdict and the command's last line")
    args = ap.parse_args(argv)
    random.seed(args.seed)
    classes = args.classes or [*RANDOM, *FIXED]
    unknown = set(classes) - set(RANDOM) - set(FIXED)
    if unknown:
        ap.error(f"unknown classes {sorted(unknown)}")
    t0 = time.time()
    results, notes = campaign(Path(args.out), classes, args.repeat, args.show)
    total = sum((sum(c.values()) for c in results.values()))
    failed = {f: sum(c[f] for c in results.values()) for f in FAILURES}
    print(f"{total} cases in {len(results)} classes, {time.time() - t0:.0f} s: "
          + ", ".join(f"{n} {f}" for f, n in failed.items()))
    for n in notes:
        print("  " + n)
    return 1 if any(failed.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
