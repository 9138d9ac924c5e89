"""The gap report's text: parameters with as many digits as their intervals carry."""

from __future__ import annotations

from vidiscover.commands.gap import _html, param_text


def test_parameters_print_to_the_digits_their_interval_carries():
    assert param_text({"theta": 2.0444716004247874},
                      {"theta": [1.0119486294599696, 3.076994571389605]}) == \
        "theta = 2.0 [1.0, 3.1]"
    assert param_text({"mu": 0.123456}, {"mu": [0.1201, 0.1268]}) == \
        "mu = 0.1235 [0.1201, 0.1268]"
    # no interval: three significant digits; strings as they are
    assert param_text({"f_s": 251.2345, "right": "linear:0.9:0.2"}) == \
        "f_s = 251; right = linear:0.9:0.2"
    assert param_text({"tau": 0.0005}, {"tau": None}) == "tau = 0.0005"


def test_report_html_is_styled_and_has_no_python_dicts():
    doc = {"recording": "rec <1>", "gap_before": 123.456789, "gap_after": 0.5123,
           "threshold": 8.0, "significant": True, "verdict": "inclination",
           "unexplained": 0.0,
           "attributed": [{"name": "inclination", "share": 0.99,
                           "params": {"theta": 2.0444716004247874},
                           "ci": {"theta": [1.0119486294599696, 3.076994571389605]}}],
           "components": {"flights": {"before": 100.0, "after": 0.2}},
           "effects": [{"name": "inclination", "gap_after": 0.5123, "shrink": 0.9958,
                        "params": {"theta": 2.0444716004247874}, "ci": None}]}
    page = _html(doc, ["waterfall.png"])
    assert "<style>" in page and "rec &lt;1&gt;" in page
    assert "{'theta'" not in page and "2.0444716004247874" not in page
    assert "theta = 2.0 [1.0, 3.1]" in page
    assert "<figcaption>" in page and "linear axis" in page


def test_waterfall_axis_is_linear_so_bar_lengths_compare():
    from types import SimpleNamespace

    import matplotlib

    matplotlib.use("Agg")
    from vidiscover.gap.components import GROUPS
    from vidiscover.gap.figures import plot_waterfall

    values = {g: 0.0 for g in GROUPS}
    big, small = GROUPS[0], GROUPS[1]
    values[big], values[small] = 100.0, 3.0
    total = sum(values.values())
    chosen = SimpleNamespace(name="inclination", gap=SimpleNamespace(total=1.0))
    report = SimpleNamespace(nominal=SimpleNamespace(gap=SimpleNamespace(by_group=lambda: values)),
                             selected=[chosen], gap_before=total, gap_after=1.0, name="rec",
                             verdict="inclination")
    ax = plot_waterfall(report)
    assert ax.get_yscale() == "linear"
    heights = {p.get_x(): p.get_height() for p in ax.patches}
    bars = [heights[k] for k in sorted(heights)]
    assert bars[0] == 100.0 and bars[1] == 3.0        # each bar as long as its value
    labels = [t.get_text() for t in ax.texts]
    assert "3" in labels and "100" in labels          # small bars are read from their labels


def test_a_law_not_excluded_by_the_recording_is_said_in_text_and_html():
    from vidiscover.commands.gap import human_gap

    doc = {"recording": "r", "gap_before": 40.0, "gap_after": 0.8, "threshold": 8.0,
           "significant": True, "verdict": "asymmetric_restitution", "unexplained": 0.02,
           "not_excluded": ["velocity_dependent_restitution"],
           "attributed": [], "components": {"flights": {"before": 40.0, "after": 0.8}},
           "effects": []}
    for text in (human_gap(doc), _html(doc, [])):
        assert "not excluded" in text.lower()
        assert "velocity_dependent_restitution" in text and "one speed" in text
    doc["not_excluded"] = []
    assert "not excluded" not in human_gap(doc).lower()
    assert "not excluded" not in _html(doc, []).lower()


def test_an_offered_effect_without_a_fit_is_said_with_its_reason():
    from types import SimpleNamespace

    from vidiscover.commands.gap import human_gap
    from vidiscover.gap.fit import not_fitted_reason

    impacts = SimpleNamespace(real=SimpleNamespace(r_pooled=0.8))
    none = SimpleNamespace(real=SimpleNamespace(r_pooled=float("nan")))
    why = not_fitted_reason(impacts, "velocity_dependent_restitution")
    # without impacts the law is not fitted for want of them, not as constants per wall
    assert "no impact" in not_fitted_reason(none, "velocity_dependent_restitution")
    assert "no impact" in not_fitted_reason(none, "asymmetric_restitution")
    assert "band" in not_fitted_reason(impacts, "sensor_resonance")
    doc = {"recording": "r", "gap_before": 40.0, "gap_after": 0.8, "threshold": 8.0,
           "significant": True, "verdict": "asymmetric_restitution", "unexplained": 0.02,
           "not_fitted": {"velocity_dependent_restitution": why},
           "attributed": [], "components": {"flights": {"before": 40.0, "after": 0.8}},
           "effects": []}
    for text in (human_gap(doc), _html(doc, [])):
        assert "not fitted" in text.lower()
        assert "velocity_dependent_restitution" in text and "beyond the precision" in text
    doc["not_fitted"] = {}
    assert "not fitted" not in human_gap(doc).lower()
    assert "not fitted" not in _html(doc, []).lower()
