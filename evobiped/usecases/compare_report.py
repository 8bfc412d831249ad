"""What a comparison reports (:mod:`.comparing`): per configuration the success rate with its Wilson 95 % interval,
the median and interquartile range of the measure, the success rate at each checkpoint (the figure's curve); per
pair of configurations Vargha and Delaney's A and the two-sided Mann-Whitney p of the measure.  The unit is the
run (one per seed): a run's measure is the median over its fresh presentations, its success that every one passed.
Written as results.json and results.md (the Markdown the command prints) and success.png."""

from __future__ import annotations

import math
from itertools import combinations
from pathlib import Path

from ..analysis.compare_stats import mann_whitney_p, median_iqr, vargha_delaney, wilson_ci
from ..analysis.retest import DEFAULT_NOISE, WALKER
from ..core.fileio import atomic_write, write_json

RESULTS_JSON, RESULTS_MD, FIGURE = "results.json", "results.md", "success.png"


def comparison_results(comparison, retests: list[dict]) -> dict:
    """The results of ``comparison`` from its runs' retests (any order)."""
    c = comparison
    by = {(r["name"], r["seed"]): r for r in retests}
    configs = []
    for name in c.names:
        runs = [by[(name, s)] for s in c.seeds]
        final = [r["checkpoints"][-1] for r in runs]
        values = [f["value"] for f in final]
        k = sum(f["success"] for f in final)
        med, q25, q75 = median_iqr(values)
        curve = []
        for i in range(c.checkpoints):
            ki = sum(r["checkpoints"][i]["success"] for r in runs)
            curve.append({"episodes": runs[0]["checkpoints"][i]["target"], "successes": ki, "runs": len(runs),
                          "wilson": list(wilson_ci(ki, len(runs)))})
        configs.append({"name": name, "runs": len(runs), "successes": k, "success_rate": k / len(runs),
                        "wilson": list(wilson_ci(k, len(runs))), "median": med, "q25": q25, "q75": q75,
                        "values": values, "success_by_seed": [bool(f["success"]) for f in final],
                        "presentations_passed": sum(sum(f["passed"]) for f in final),
                        "presentations": sum(len(f["passed"]) for f in final),
                        "episodes": [r["episodes"] for r in runs], "generations": [r["generations"] for r in runs],
                        "curve": curve})
    pairs = [{"a": a["name"], "b": b["name"], "A": vargha_delaney(a["values"], b["values"]),
              "p": mann_whitney_p(a["values"], b["values"])} for a, b in combinations(configs, 2)]
    return {"budget": c.budget, "seeds": list(c.seeds), "trials": c.trials, "noise": c.noise, "measure": c.measure,
            "success": c.success, "configurations": configs, "pairs": pairs}


def _n(x: float, digits: int = 3) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{x:.{digits}f}"


def criterion_text(success: str) -> str:
    """The success criterion in words."""
    if success == "walker":
        return (f"the walker test (no fall in {WALKER['seconds']:g} s; a walk by the gait lab's criteria over the "
                f"first {WALKER['window']:g} s)")
    if success == "forward":
        return (f"the forward-walker test (no fall in {WALKER['seconds']:g} s, at least {WALKER['min_distance']:g} m "
                f"in the first {WALKER['window']:g} s within {WALKER['heading_limit']:g} deg of the initial facing)")
    return success


def markdown(results: dict) -> str:
    """The comparison as Markdown: the configurations' table, then the pairs'."""
    r = results
    table = DEFAULT_NOISE if r["noise"] is None else r["noise"]
    noise = ", ".join(f"{k} = {v}" for k, v in table.items()) or "none"
    lines = [f"Budget {r['budget']} episodes per run; seeds {r['seeds'][0]}..{r['seeds'][-1]}; each run's final policy "
             f"on {r['trials']} fresh presentations (noise: {noise}); success: {criterion_text(r['success'])} in every "
             f"presentation; measure: {r['measure']} (the median over a run's presentations).", "",
             f"| configuration | runs | successes | success rate | Wilson 95 % | median {r['measure']} | IQR |",
             "|---|---|---|---|---|---|---|"]
    for c in r["configurations"]:
        lo, hi = c["wilson"]
        lines.append(f"| {c['name']} | {c['runs']} | {c['successes']} | {_n(c['success_rate'], 2)} | "
                     f"{_n(lo, 2)}–{_n(hi, 2)} | {_n(c['median'])} | {_n(c['q25'])}–{_n(c['q75'])} |")
    if r["pairs"]:
        lines += ["", f"| pair | Vargha–Delaney A ({r['measure']}) | Mann–Whitney p (two-sided) |", "|---|---|---|"]
        lines += [f"| {p['a']} vs {p['b']} | {_n(p['A'], 2)} | {_n(p['p'], 3)} |" for p in r["pairs"]]
    return "\n".join(lines) + "\n"


def write_comparison(directory: Path, comparison, retests: list[dict], say=None) -> dict:
    """results.json, results.md and success.png in ``directory``, one set (``say(line)`` hears that the previous
    writing of them was cut short); returns the results."""
    from ..record.png.compare_figure import success_figure

    from ..files.rundir.output_set import output_set

    results = comparison_results(comparison, retests)
    with output_set("compare", [directory / RESULTS_JSON, directory / RESULTS_MD, directory / FIGURE], say=say):
        write_json(directory / RESULTS_JSON, results)  # one set: never new tables beside an old figure
        atomic_write(directory / RESULTS_MD, markdown(results))
        success_figure(results, directory / FIGURE)
    return results
