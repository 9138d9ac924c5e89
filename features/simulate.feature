Feature: Simulate a vibro-impact rig
  As a researcher I want realistic recordings of a ball rattling in a clearance,
  with their ground truth, so that I can test estimators before I trust them on
  my rig's data.

  Scenario: Simulating the paper's rig at 9 mm
    Given the paper preset with a half-clearance of 9 mm
    When I simulate it with seed 1
    Then I get a recording with columns t, x, a and xe sampled at 6400 Hz
    And its ground truth lists impacts on both walls
    And the ground truth names a regime label

  Scenario Outline: Switching on one effect of the catalogue
    Given the paper preset with a half-clearance of 9 mm
    When I simulate it with the effect "<effect>" and seed 2
    Then the ground truth records the effect "<name>"
    And momentum is conserved at every impact

    Examples:
      | effect                                | name                   |
      | coulomb_friction=0.3                  | coulomb_friction       |
      | inclination=2                         | inclination            |
      | asymmetric_restitution=0.9,0.3        | asymmetric_restitution |
      | clearance_error=0.0005                | clearance_error        |
      | excitation_distortion=0.1             | excitation_distortion  |
      | sensor_resonance                      | sensor_resonance       |
      | contact_duration=0.0001               | contact_duration       |

  Scenario: Chatter does not hang the simulator
    Given the paper preset with a half-clearance of 9 mm
    When I simulate it with the effects "asymmetric_restitution=0.88,0.2" and "inclination=3"
    Then the simulation completes
    And the ground truth reports sticking phases

  Scenario: A mistyped effect is refused with one line
    When I run "vidiscover simulate --effect friction=0.3 --out rec.csv"
    Then the command fails with status 2
    And the error message says "unknown effect 'friction'"
    And no file is written
