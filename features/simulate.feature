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

  Scenario: Compliant walls recorded behind a causal anti-alias filter
    When I run "vidiscover simulate --preset paper --b 0.009 --contact kelvin-voigt:k=3e7,r=0.7 --anti-alias butter:4:2500 --settle 2 --duration 1 --out rec.csv"
    Then the command succeeds
    And the files rec.csv, rec.json and rec.truth.json are written
    And every impact in rec.truth.json has t_in < t_out

  Scenario: Raw mV columns with bias, offset and a 16-bit ADC are read back by analyze
    When I run "vidiscover simulate --b 0.009 --units mV --a-bias 0.3 --x-offset 0.001 --adc-bits 16 --settle 2 --duration 1 --out raw.csv"
    Then the command succeeds
    And raw.csv has the columns t, x_mV, a_mV and xe_mV
    And "vidiscover analyze raw.csv --out ana --no-figures" finds impacts in it

  Scenario: Another rig, set from the command line
    When I run "vidiscover simulate --m1 3 --k1 15000 --m2 0.05 --amplitude 0.0006 --frequency 10 --b 0.006 --sample-rate 8192 --settle 2 --duration 1 --out rig.csv --json"
    Then the command succeeds
    And rig.json records m1 3, k1 15000, m2 0.05 and a sample rate of 8192 Hz

  Scenario Outline: Bad contact, filter or rig specs are refused with one line
    When I run "vidiscover simulate <args> --settle 2 --duration 1 --out rec.csv"
    Then the command fails with status 2
    And the error message says "<message>"
    And no file is written

    Examples:
      | args                                        | message            |
      | --contact springy:k=1e7                     | springy            |
      | --contact kelvin-voigt:k=-3e7,r=0.7         | k                  |
      | --contact kelvin-voigt:k=3e7,r=1.7          | r                  |
      | --contact right=kelvin-voigt:k=3e7,r=0.7    | left               |
      | --anti-alias elliptic:4:2500                | elliptic           |
      | --anti-alias butter:4:9000                  | 9000               |
      | --anti-alias butter:x:2500                  | butter:x:2500      |
      | --m1 -3                                     | m1 must be > 0     |
      | --frequency 0                               | frequency must be > 0 |
      | --full-scale z=0.01                         | --full-scale       |
      | --mount-resonance fast                      | --mount-resonance  |
