import math

import numpy as np
import pytest

from vidiscover.errors import InputError
from vidiscover.regimes.chaos import _msd, irregular_beyond_noise, zero_one_test


def logistic(r, n, x0=0.3, burn=500):
    x = np.empty(n + burn)
    x[0] = x0
    for j in range(1, x.size):
        x[j] = r * x[j - 1] * (1 - x[j - 1])
    return x[burn:]


def test_msd_matches_the_direct_sum():
    rng = np.random.default_rng(1)
    p = rng.normal(size=(3, 200)).cumsum(axis=1)
    direct = np.array([[np.mean((row[n:] - row[:-n]) ** 2) for n in range(1, 21)]
                       for row in p])
    np.testing.assert_allclose(_msd(p, 20), direct, rtol=1e-9)


@pytest.mark.parametrize("r", [3.9, 3.97, 4.0])
def test_logistic_map_in_its_chaotic_range_gives_k_near_one(r):
    assert zero_one_test(logistic(r, 2000), seed=1).K > 0.95


@pytest.mark.parametrize("r", [3.2, 3.5, 3.83])   # periods 2, 4 and 3
def test_periodic_logistic_orbits_give_k_near_zero(r):
    assert abs(zero_one_test(logistic(r, 2000), seed=1).K) < 0.05


def test_quasi_periodic_sequence_gives_k_near_zero():
    j = np.arange(2000)
    phi = np.sin(2 * math.pi * j * (math.sqrt(5) - 1) / 2) + 0.5 * np.cos(math.sqrt(2) * j)
    assert abs(zero_one_test(phi, seed=2).K) < 0.1


def test_iid_noise_looks_chaotic_so_precision_must_be_checked_separately():
    rng = np.random.default_rng(3)
    assert zero_one_test(rng.normal(size=2000), seed=0).K > 0.9
    # a period-2 sequence under noise as large as its jumps reads as irregular ...
    noisy = np.tile([1.0, 2.0], 1000) + rng.normal(0, 0.5, 2000)
    assert zero_one_test(noisy, seed=0).K > 0.5
    # ... but its irregular part is no larger than the measurement precision
    assert not irregular_beyond_noise(noisy, precision=0.5)
    # small noise leaves a periodic sequence regular
    assert abs(zero_one_test(np.tile([1.0, 2.0], 1000) + rng.normal(0, 1e-3, 2000)).K) < 0.05
    assert irregular_beyond_noise(logistic(3.97, 2000), precision=1e-3)


def test_same_seed_same_result_and_constant_is_regular():
    x = logistic(3.97, 500)
    assert zero_one_test(x, seed=5).K == zero_one_test(x, seed=5).K
    assert zero_one_test(np.ones(500)).K == 0.0


def test_short_or_bad_sequences_are_refused():
    with pytest.raises(InputError, match="at least 100 samples"):
        zero_one_test(np.ones(50))
    with pytest.raises(InputError, match="finite"):
        zero_one_test(np.r_[np.ones(200), np.nan])
