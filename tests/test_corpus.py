import math

import numpy as np
import pytest

from vidiscover.corpus import N_CASES, N_SUITE, RANGES, realism_case, realism_corpus
from vidiscover.errors import InputError


def test_cases_are_a_pure_function_of_split_and_index():
    assert realism_case("dev", 3) == realism_case("dev", 3)
    assert realism_case("dev", 3) != realism_case("dev", 4)
    splits = [{c.params for c in realism_corpus(name, 8)}
              for name in ("dev", "test", "holdout", "holdout2", "holdout3",
                           "holdout4", "holdout5", "holdout6", "holdout7", "holdout8",
                           "holdout9", "holdout10", "holdout11", "holdout12",
                           "holdout13", "holdout14", "holdout15", "holdout16")]
    for i, one in enumerate(splits):
        assert len(one) == 8
        for other in splits[i + 1:]:
            assert not one & other


def test_draws_stay_in_their_ranges(realism_dev):
    assert len(realism_dev) == N_SUITE <= N_CASES["dev"]
    for c in realism_dev:
        f0 = math.sqrt(c.k1 / c.m1) / (2 * math.pi)
        assert RANGES["m1"][0] <= c.m1 <= RANGES["m1"][1]
        assert RANGES["f0"][0] <= f0 <= RANGES["f0"][1]
        assert 0.7 <= c.frequency / f0 <= 1.2
        assert 0.005 <= c.m2 / c.m1 <= 0.05
        assert 0.003 <= c.b <= 0.030
        assert 0.0 <= c.mu <= 0.3 and abs(c.theta) <= 3.0
        assert len(c.contact) == 2


def test_the_corpus_covers_both_contact_models_and_every_filter_kind():
    cases = realism_corpus("test")
    kinds = {spec.split("=", 1)[1].split(":")[0] for c in cases for spec in c.contact}
    assert kinds == {"kelvin-voigt", "hunt-crossley"}
    assert {c.sensors["anti_alias"] for c in cases} == {"linear-phase", "butter", "bessel",
                                                        "cheby1"}
    assert any(c.mu > 0 for c in cases) and any(c.theta != 0 for c in cases)
    assert len({c.sensors["sample_rate"] for c in cases}) >= 4


def test_bad_split_or_size_is_one_line():
    with pytest.raises(InputError, match="unknown corpus split"):
        realism_case("train", 0)
    with pytest.raises(InputError, match="has 96 cases"):
        realism_corpus("dev", 97)


def test_a_dev_case_simulates_with_contact_episodes(realism_dev):
    sim = realism_dev[3].simulate()
    imps = sim.truth.impacts
    assert imps.n > 0
    assert np.all(imps.t_out > imps.t_in)
    assert sim.recording.sample_rate == realism_dev[3].sensors["sample_rate"]


@pytest.mark.slow
def test_every_dev_case_impacts(realism_dev):
    for case in realism_dev:
        sim = case.simulate()
        assert sim.truth.impacts.n >= 10, case.name
