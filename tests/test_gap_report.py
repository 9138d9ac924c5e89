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
