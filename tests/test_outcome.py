"""evobiped.files.outcome and evobiped.core.provenance: what a replay in another numerical environment compares."""

from evobiped.core import provenance
from evobiped.files.outcome import Tolerance, compare


def row(**kw):
    return {"fell": False, "end_time": 50.0, "distance": 20.0, "heading_deg": 3.0, **kw}


def replayed(*rows):
    return {"fell": any(r["fell"] for r in rows), "end_time": min(r["end_time"] for r in rows), "rows": list(rows)}


def test_an_outcome_within_tolerance_holds_and_its_drift_is_reported():
    drift, failures = compare(replayed(row()), replayed(row(distance=20.9, heading_deg=7.5)))
    assert failures == []  # 0.9 m <= max(0.5, 5 % of 20) = 1.0 m; 4.5 deg <= 5 deg
    assert "distance 20.90 m (stored 20.00 m, +0.9000 m)" in drift and "up 50 s (as stored)" in drift


def test_each_quantity_outside_its_tolerance_is_a_failure():
    stored = replayed(row(to_target=0.1), row(to_target=0.2))
    got = replayed(row(to_target=0.7), row(fell=True, end_time=12.5, distance=18.0, heading_deg=-9.0, to_target=0.3))
    _, failures = compare(stored, got)
    assert failures == [
        "fell at 12.50 s, stored: stayed up",
        "presentation 1: ended 0.70 m from its target, stored 0.10 m (allowed +0.5 m)",
        "presentation 2: fell at 12.50 s, stored: stayed up",
        "presentation 2: distance 18.00 m, stored 20.00 m (allowed +-1.00 m)",
        "presentation 2: heading -9.0 deg, stored +3.0 deg (allowed +-5 deg)",
    ]


def test_headings_compare_across_the_backwards_seam_and_a_looser_tolerance_passes():
    _, failures = compare(replayed(row(heading_deg=179.0)), replayed(row(heading_deg=-178.0)))
    assert failures == []  # 3 deg apart, not 357
    assert compare(replayed(row()), replayed(row(distance=25.0)), Tolerance(distance_rel=0.3))[1] == []


def test_a_partial_stored_outcome_compares_what_it_has():
    """An older file: fell and end time of the genome only; a run's best: the first presentation's walk."""
    assert compare({"fell": False, "end_time": 50.0}, replayed(row(), row(distance=1.0)))[1] == []
    assert compare({"fell": False, "end_time": 50.0, "rows": [{"distance": 20.0}]},
                   replayed(row(distance=30.0), row()))[1] == [
        "presentation 1: distance 30.00 m, stored 20.00 m (allowed +-1.00 m)"]
    assert compare({"fell": True, "end_time": 3.0}, replayed(row()))[1] == ["stayed up, stored: fell at 3.00 s"]


def test_the_environment_names_what_decides_the_last_bits():
    here = provenance.current()
    assert provenance.differences(here, here) == []
    assert provenance.differences(None) == ["no environment recorded"]
    other = {**here, "numpy_simd": ["X86_V3"], "numpy": "1.26.4", "python": "3.99"}  # Python alone does not count
    assert provenance.differences(other, {**here, "numpy_simd": ["X86_V3", "X86_V4"]}) == [
        f"numpy 1.26.4 -> {here['numpy']}", "numpy SIMD X86_V3 -> X86_V3, X86_V4"]
