import math

import pytest

from vidiscover import InputError, SystemParams, preset


def test_paper_preset_matches_table_1_and_reduced_parameters():
    p = preset("paper")
    assert (p.m1, p.c1, p.k1, p.m2) == (4.168, 3.02, 11.47e3, 0.032)
    # Table 1: epsilon = 0.76 %, lambda = 1.80
    assert p.epsilon == pytest.approx(0.0077, abs=5e-5)
    assert p.lambda_ == pytest.approx(1.80, abs=0.005)
    assert p.omega0 == pytest.approx(math.sqrt(11.47e3 / 4.168))
    assert p.Omega == pytest.approx(2 * math.pi * 8.0 / p.omega0)
    assert p.G == pytest.approx(0.5e-3 / p.epsilon)


@pytest.mark.parametrize("field,value,match", [
    ("b", -0.009, r"b must be > 0"),
    ("b", 9.0, r"b = 9.0 m is implausibly large.*0\.009 for 9 mm"),
    ("m1", 0.0, r"m1 must be > 0"),
    ("m2", -1.0, r"m2 must be > 0"),
    ("r", 1.2, r"r must be in \[0, 1\]"),
    ("amplitude", 0.5, r"amplitude = 0.5 .*implausibly large"),
    ("c1", -1.0, r"c1 must be >= 0"),
    ("c1", 1e4, r"overdamped"),
    ("frequency", float("nan"), r"frequency must be a finite number"),
])
def test_invalid_parameters_are_named_with_their_rule(field, value, match):
    with pytest.raises(InputError, match=match):
        SystemParams(**{field: value})


def test_replace_rejects_unknown_names():
    with pytest.raises(InputError, match="unknown parameter.*mass"):
        preset("paper").replace(mass=1.0)
    with pytest.raises(InputError, match="unknown preset 'papr'"):
        preset("papr")
