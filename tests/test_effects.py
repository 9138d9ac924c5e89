import numpy as np
import pytest

from vidiscover import EFFECTS, Effects, InputError, RestitutionLaw
from vidiscover.effects import EXTRA_EFFECTS

CONTRACT_NAMES = {"asymmetric_restitution", "velocity_dependent_restitution",
                  "coulomb_friction", "inclination", "sensor_resonance",
                  "excitation_distortion", "clearance_error", "contact_duration"}


def test_catalogue_names_are_the_design_contract():
    assert set(EFFECTS) == CONTRACT_NAMES
    assert not set(EXTRA_EFFECTS) & CONTRACT_NAMES


@pytest.mark.parametrize("name", sorted(EFFECTS) + sorted(EXTRA_EFFECTS))
def test_every_effect_switches_on_with_defaults_and_round_trips(name):
    fx = Effects.parse([name])
    assert fx.names == [name]
    again = Effects.from_dict(fx.to_dict())
    assert again.to_dict() == fx.to_dict()
    assert name in fx.describe()


def test_positional_and_keyword_values():
    fx = Effects.parse(["asymmetric_restitution=0.9,0.3", "inclination=theta=2.5",
                        "coulomb_friction=0.2"])
    assert fx.value("asymmetric_restitution", "r_right") == 0.9
    assert fx.value("asymmetric_restitution", "r_left") == 0.3
    assert fx.theta_deg == 2.5 and fx.mu == 0.2
    laws = fx.restitution_laws(0.5)
    assert laws["right"](0.7) == 0.9 and laws["left"](0.7) == 0.3


def test_velocity_dependent_law_overrides_constant_ones():
    fx = Effects.parse(["velocity_dependent_restitution=right=power:0.3:0.5,left=linear:0.4:0.2"])
    laws = fx.restitution_laws(0.88)
    assert laws["right"](0.25) == pytest.approx(1 - 0.3 * 0.5)
    assert laws["left"](0.5) == pytest.approx(0.4 - 0.1)


@pytest.mark.parametrize("item,match", [
    ("friction=0.3", r"unknown effect 'friction'.*coulomb_friction"),
    ("coulomb_friction=-0.1", r"coulomb_friction: mu must be in \[0.0, 1.5\], was -0.1"),
    ("inclination=1,2", r"inclination takes at most 1 value"),
    ("asymmetric_restitution=r_middle=0.3", r"unknown parameter\(s\) r_middle"),
    ("velocity_dependent_restitution=right=cubic:1", r"kind must be one of"),
    ("contact_duration=0", r"tau must be in \(0.0, 0.005\]"),
])
def test_bad_effects_give_one_line_errors(item, match):
    with pytest.raises(InputError, match=match) as err:
        Effects.parse([item])
    assert "\n" not in str(err.value)


def test_effect_given_twice_is_refused():
    with pytest.raises(InputError, match="given twice"):
        Effects.parse(["inclination=1", "inclination=2"])


@pytest.mark.parametrize("spec,v,expected", [
    ("0.7", 1.3, 0.7),
    ("constant:0.7", 0.1, 0.7),
    ("linear:0.95:0.1", 0.5, 0.9),
    ("power:0.3:0.5", 0.64, 1 - 0.3 * 0.8),
    ("linear:0.5:1.0", 2.0, 0.0),  # clipped to [0, 1]
])
def test_restitution_laws(spec, v, expected):
    law = RestitutionLaw.parse(spec)
    assert law(v) == pytest.approx(expected)
    assert law(np.array([v, v])) == pytest.approx([expected, expected])
    assert RestitutionLaw.parse(law.spec) == law
    assert law.formula.startswith("r = ")


def test_effects_pickle_round_trip_for_worker_processes():
    import pickle

    from vidiscover.effects import Effects

    eff = Effects.parse(["coulomb_friction=0.3", "asymmetric_restitution=0.88,0.2",
                         "velocity_dependent_restitution=right=linear:0.9:0.1"])
    back = pickle.loads(pickle.dumps(eff))
    assert back.to_dict() == eff.to_dict()
    assert back.mu == eff.mu
