"""Feedback of an identified flight law into the analysis (issue 4, item 3).

Ground truth: constant r = 0.88 on both walls, so the per-wall RMS of r must come
out 0.88 once the flights are reconstructed with the right friction and tilt.
Tolerance: 0.02 (the issue's), and the uncorrected analysis must be off by more
than 0.005 so that the test shows the correction doing something.
"""

import functools
import json

import numpy as np
import pytest
from click.testing import CliRunner

from vidiscover import Effects, InputError, preset, record, simulate
from vidiscover.analysis import analyze
from vidiscover.cli import main
from vidiscover.io import write_recording

R = 0.88


@functools.cache
def _rec(b, effects):
    res = simulate(preset("paper", b=b), Effects.parse(["asymmetric_restitution=0.88,0.88",
                                                         *effects]),
                   settle=8.0, duration=5.12)
    return record(res, seed=3)


def _rms(out):
    rest = out.summary()["restitution"]
    return rest["right"]["rms"], rest["left"]["rms"]


@pytest.mark.parametrize("effects, law", [
    (("inclination=2",), (0.0, 2.0)),
    (("inclination=1", "coulomb_friction=0.1"), (0.1, 1.0)),
])
def test_known_law_removes_the_bias_of_r(effects, law):
    rec, _ = _rec(0.009, effects)
    plain = _rms(analyze(rec, n_boot=0))
    fixed = analyze(rec, n_boot=0, flight_law=law)
    assert max(abs(v - R) for v in plain) > 0.005, plain
    right, left = _rms(fixed)
    assert abs(right - R) <= 0.02 and abs(left - R) <= 0.02, (right, left)
    assert fixed.theta_deg == law[1] and fixed.mu == law[0]
    assert fixed.summary()["theta_deg"] == law[1]


def test_discovered_law_feeds_back():
    from vidiscover.discovery import discover_flight_law

    effects = ("inclination=1", "coulomb_friction=0.1")
    analyses = [analyze(_rec(b, effects)[0], n_boot=0) for b in (0.006, 0.0075, 0.009)]
    law = discover_flight_law(analyses, seed=0, n_boot=20)
    assert abs(law.mu - 0.1) <= 0.03 and abs(law.theta_deg - 1.0) <= 0.3, law.equation
    out = analyze(analyses[-1].recording, n_boot=0, flight_law=law)
    right, left = _rms(out)
    assert abs(right - R) <= 0.02 and abs(left - R) <= 0.02, (right, left)


def test_zero_tilt_law_is_the_plain_friction_analysis():
    rec, _ = _rec(0.009, ("coulomb_friction=0.1",))
    a = analyze(rec, mu=0.1, n_boot=0)
    b = analyze(rec, n_boot=0, flight_law=(0.1, 0.0))
    np.testing.assert_array_equal(a.impact_table["r"], b.impact_table["r"])


@pytest.mark.parametrize("law, words", [("fast", "FlightLawResult or a pair"),
                                        ((0.1, 95.0), "theta_deg must be in")])
def test_bad_flight_law_is_an_input_error(law, words):
    rec, _ = _rec(0.009, ("inclination=2",))
    with pytest.raises(InputError, match=words):
        analyze(rec, flight_law=law)


def test_cli_takes_a_discovery_json(tmp_path):
    rec, truth = _rec(0.009, ("inclination=2",))
    path = tmp_path / "rec.csv"
    write_recording(rec, path, truth=truth)
    law = tmp_path / "discovery.json"
    law.write_text(json.dumps({"flight": {"mu": 0.0, "theta_deg": 2.0}}))
    res = CliRunner().invoke(main, ["analyze", str(path), "--out", str(tmp_path / "o"),
                                    "--flight-law", str(law), "--no-figures", "--json"])
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["theta_deg"] == 2.0
    assert abs(doc["restitution"]["right"]["rms"] - R) <= 0.02
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"flight": None}))
    res = CliRunner().invoke(main, ["analyze", str(path), "--out", str(tmp_path / "p"),
                                    "--flight-law", str(bad)])
    assert res.exit_code == 2 and "has no identified flight law" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "p").exists()
