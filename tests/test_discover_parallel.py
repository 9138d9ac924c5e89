"""``discover(..., n_jobs=...)``: the same result in forked workers as in this process.

The flight law identified here (friction) sends the recordings to be analysed again
with it, so the speculative impact laws fitted in the workers during the flight law are
discarded and fitted again: that path is checked too.
"""

from __future__ import annotations

import pytest

from vidiscover import Effects, preset, record, simulate
from vidiscover._workers import can_fork
from vidiscover.discovery import discover
from vidiscover.errors import InputError


@pytest.fixture(scope="module")
def friction_recordings():
    fx = Effects.parse(["coulomb_friction=0.3", "asymmetric_restitution=0.88,0.7"])
    return [record(simulate(preset("paper", b=b), fx, settle=5.0, duration=3.0), seed=k)[0]
            for k, b in enumerate((0.006, 0.0075, 0.009))]


@pytest.mark.skipif(not can_fork(), reason="workers are forked (Linux) or not used")
def test_workers_give_the_serial_result_also_when_the_flight_law_refines(
        friction_recordings):
    one = discover(friction_recordings, n_boot=20, n_jobs=1)
    two = discover(friction_recordings, n_boot=20, n_jobs=2)
    assert one.mu_impacts > 0.2          # identified friction: analysed again with it
    assert one.summary() == two.summary()
    for side in ("right", "left"):
        assert one.impact_data[side].equals(two.impact_data[side])
        assert one.impact_laws[side].candidates.equals(two.impact_laws[side].candidates)
    assert one.flight_residuals().equals(two.flight_residuals())


@pytest.mark.parametrize("bad", [0, -1, 1.5, True])
def test_bad_n_jobs_is_an_input_error(friction_recordings, bad):
    with pytest.raises(InputError, match="n_jobs must be a positive integer"):
        discover(friction_recordings[:1], n_boot=0, flight=False, n_jobs=bad)


def test_analyses_given_as_such_are_used_as_they_are(friction_recordings):
    """Nothing to analyse: the analyses passed in are the result's (not copies)."""
    from vidiscover.analysis import analyze

    an = analyze(friction_recordings[0], n_boot=0)
    res = discover([an], n_boot=0, flight=False, n_jobs=2)
    assert res.analyses[0] is an


@pytest.mark.skipif(not can_fork(), reason="workers are forked (Linux) or not used")
@pytest.mark.parametrize("n_jobs", [1, 2])
def test_an_error_in_a_worker_reaches_the_caller_as_it_is(friction_recordings, monkeypatch,
                                                          n_jobs):
    """A recording that cannot be analysed fails the call with its own InputError, whether
    it was analysed here or in a worker (the workers fork with this patch in place)."""
    import vidiscover.discovery.pipeline as pipeline

    real = pipeline.analyze
    first = friction_recordings[0]

    def analyze(rec, **kw):   # a worker gets a copy of the second recording, not `first`
        if rec is not first:
            raise InputError("recording 2: no impacts found; check the file")
        return real(rec, **kw)

    monkeypatch.setattr(pipeline, "analyze", analyze)
    with pytest.raises(InputError, match="recording 2: no impacts found"):
        discover(friction_recordings[:2], n_boot=0, flight=False, n_jobs=n_jobs)


@pytest.mark.skipif(not can_fork(), reason="workers are forked (Linux) or not used")
def test_workers_send_back_analyses_read_in_a_causal_filters_time_frame():
    """Behind a causal anti-alias filter the LO is read one filter delay later, and the
    analysis keeps that frame shift; a worker must be able to send it back (it held
    local functions once, and discover failed with a pickling traceback on such
    recordings: realism test-033, Chebyshev-8, laser on its rails)."""
    from vidiscover.corpus import realism_case

    rec = realism_case("test", 33).simulate(label=False).recording
    one = discover([rec, rec], n_boot=0, flight=False, n_jobs=1)
    two = discover([rec, rec], n_boot=0, flight=False, n_jobs=2)
    assert two.analyses[0].reconstruction._shift is not None
    assert one.summary() == two.summary()
