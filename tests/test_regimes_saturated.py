"""Regimes of saturated recordings (sat26).

A recording whose accelerometer sits on its rail for many cycles (longer than a clipped
pulse: the forced response itself saturates and hides the impacts there) cannot count
its impacts: finding few is no evidence of none. A laser at its full scale hides no
impact and does not count. Every false ``no_impact`` of the realism corpus's spent splits was such a
recording; the rules and ``classify`` now claim ``no_impact`` only when the impacts
that the saturated cycles could hide (one per cycle) stay below the label's 0.05 per
cycle, and refuse the label (``not_classified``) otherwise.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest


def _frame(ipc, sat):
    return pd.DataFrame({"merged_per_cycle": ipc, "impacts_per_cycle": ipc,
                         "merged_cycle_share": np.zeros(len(ipc)),
                         "saturated_cycle_share": sat})


def test_rules_claim_no_impact_only_where_the_saturated_cycles_cannot_hide_enough():
    from vidiscover.regimes.classifier import REFUSED, RuleBaseline

    ipc = np.array([0.0, 0.0, 0.0, 0.03, 0.03, 0.0])
    sat = np.array([0.0, 0.04, 0.05, 0.01, 0.02, np.nan])
    got = RuleBaseline().predict(_frame(ipc, sat))
    # ipc + saturated share < 0.05: no_impact; at or beyond it: refused; NaN: unknown, 0
    want = ["no_impact", "no_impact", REFUSED, "no_impact", REFUSED, "no_impact"]
    assert list(got) == want


def test_a_table_without_the_saturation_column_reads_as_before():
    from vidiscover.regimes.classifier import RuleBaseline

    frame = _frame(np.array([0.0, 0.01]), np.array([0.9, 0.9])).drop(
        columns="saturated_cycle_share")
    assert list(RuleBaseline().predict(frame)) == ["no_impact", "no_impact"]


def test_the_model_does_not_read_the_saturation_feature():
    from vidiscover.regimes.classifier import load_default_model, model_features
    from vidiscover.regimes.features import ALL_FEATURES

    assert "saturated_cycle_share" in ALL_FEATURES
    assert "saturated_cycle_share" not in model_features()
    assert "saturated_cycle_share" not in load_default_model().feature_names


def test_classifier_no_impact_on_a_saturated_row_is_refused():
    # the classifier reads the same missing impacts: its no_impact is refused too, while
    # an impacting label it gives stands
    from dataclasses import replace

    from vidiscover.regimes.classifier import REFUSED, load_default_model

    model = replace(load_default_model(), rule_min_proba={})   # no probabilities needed
    rows = _frame(np.array([0.0, 0.0, 0.0]), np.array([0.8, 0.8, 0.0]))
    clf = np.array(["no_impact", "multi_ipc", "no_impact"], dtype=object)
    labels, methods = model.decide(rows, clf=clf)
    # row 0: rules refuse (not a kept label), classifier's no_impact refused; row 1: the
    # classifier's multi_ipc; row 2: unsaturated, the rules' no_impact
    assert list(labels) == [REFUSED, "multi_ipc", "no_impact"]
    assert list(methods) == ["refused", "classifier", "rules"]


def test_saturated_cycle_share_counts_the_railed_cycles():
    # a paper-rig recording whose accelerometer range lies below the forced response's
    # peak: the rail is reached in every cycle; the same recording with the default
    # (unlimited) range has no saturated cycle
    from vidiscover import Effects, preset
    from vidiscover.analysis import analyze
    from vidiscover.regimes.features import ALL_FEATURES
    from vidiscover.sensors import SensorConfig
    from vidiscover.workflows import simulate_to_memory

    p = preset("paper")
    shares = []
    for a_range in (None, 0.5 * (2 * np.pi * p.frequency) ** 2 * p.amplitude):
        rec, _, _ = simulate_to_memory(p, Effects(), sensors=SensorConfig(a_range=a_range),
                                       seed=5, duration=2.0)
        out = analyze(rec, n_boot=0, features=ALL_FEATURES)
        shares.append(out.features["saturated_cycle_share"])
    assert shares[0] == 0.0
    assert shares[1] > 0.9


def test_a_saturated_corpus_recording_is_not_called_no_impact():
    # holdout13-086 (spent): laser on +/-10 mm for 82 % of the samples, accelerometer
    # on its rail for 60 %, in every cycle; no impact found although the ball impacts
    # every cycle (truth multi_ipc). The rules said no_impact before.
    from vidiscover.corpus import realism_case
    from vidiscover.regimes.classifier import load_default_model

    sim = realism_case("holdout13", 86).simulate()
    assert sim.truth.label != "no_impact"
    c = load_default_model().classify(sim.recording)
    assert c.label != "no_impact"
    assert c.features["saturated_cycle_share"] > 0.9
    if c.method == "refused":
        assert c.label == "not_classified"
        assert c.warnings[0].startswith("not classified: the accelerometer is saturated")


@pytest.mark.parametrize("split_case", [("holdout13", 0)])
def test_an_unsaturated_recording_reads_zero(split_case):
    from vidiscover.corpus import realism_case
    from vidiscover.regimes.classifier import load_default_model

    sim = realism_case(*split_case).simulate()
    c = load_default_model().classify(sim.recording)
    assert c.method != "refused"
    assert c.features["saturated_cycle_share"] == 0.0


def test_a_railed_laser_alone_does_not_refuse_no_impact():
    # a paper-rig record without impacts whose laser (16-bit, +/-0.1 mm) reads its full
    # scale in every cycle: the accelerometer still sees every impact there is, so the
    # record stays no_impact (counting the laser's rails refused the rules' label, and
    # the classifier then said chaotic)
    from vidiscover import Effects, preset
    from vidiscover.regimes.classifier import load_default_model
    from vidiscover.sensors import SensorConfig
    from vidiscover.workflows import simulate_to_memory

    p = preset("paper", b=0.03).replace(amplitude=0.1e-3, frequency=6.0)
    sen = SensorConfig(adc_bits=16, x_full_scale=1e-4)
    rec, truth, _ = simulate_to_memory(p, Effects(), sensors=sen, seed=5)
    assert truth.label == "no_impact"
    assert np.mean(np.abs(rec.x) >= 0.99e-4) > 0.2         # the laser is railed
    c = load_default_model().classify(rec)
    assert c.features["saturated_cycle_share"] == 0.0
    assert c.label == "no_impact"


def test_feature_context_of_an_analysis_keeps_the_saturation():
    # features of another set computed on an analysis already made see the same
    # saturated cycles as the analysis's own (the context takes them from the recording)
    from vidiscover import Effects, preset
    from vidiscover.analysis import analyze
    from vidiscover.analysis.returnmap import compute_features
    from vidiscover.regimes.dataset import feature_context
    from vidiscover.regimes.features import ALL_FEATURES
    from vidiscover.sensors import SensorConfig
    from vidiscover.workflows import simulate_to_memory

    p = preset("paper")
    a_range = 0.5 * (2 * np.pi * p.frequency) ** 2 * p.amplitude
    rec, _, _ = simulate_to_memory(p, Effects(), sensors=SensorConfig(a_range=a_range),
                                   seed=5, duration=2.0)
    out = analyze(rec, n_boot=0, features=ALL_FEATURES)
    again = compute_features(feature_context(out), ALL_FEATURES)
    assert out.features["saturated_cycle_share"] > 0.9
    assert again["saturated_cycle_share"] == out.features["saturated_cycle_share"]


def test_a_refusal_is_said_as_it_is_and_other_warnings_as_out_of_domain():
    from vidiscover.regimes.classifier import refusal_message, warning_text

    why = refusal_message({"saturated_cycle_share": 1.0, "merged_per_cycle": 0.0})
    assert warning_text(why) == why
    assert warning_text("feature dt_max = 3.1 above 2.0").startswith(
        "outside the training domain (feature dt_max")


def test_only_saturated_rows_below_the_bound_are_refused():
    # an unsaturated row with 0.06 impacts per cycle counted, which a classifier may
    # still call no_impact, is no refusal (it was: ipc alone reached the bound)
    from vidiscover.regimes.classifier import RuleBaseline

    rows = _frame(np.array([0.06, 0.0, 0.02, 0.02]), np.array([0.0, 0.0, 0.5, 0.01]))
    assert list(RuleBaseline().refused(rows)) == [False, False, True, False]
