Feature: Discover how a wall's restitution depends on impact speed
  As a researcher with recordings of my rig at several clearances, I want the
  restitution law of each wall discovered from the pooled impacts, with its
  uncertainty and a comparison with a constant r, so that I know whether a
  constant r is good enough for my model.

  Scenario Outline: A velocity-dependent law is recovered from a clearance sweep
    Given recordings simulated at 6, 7.5 and 9 mm with right wall "<right>" and left wall "<left>"
    When I run discover on them
    Then the right wall law has the form of "<right>"
    And the left wall law has the form of "<left>"
    And each fitted law is within 0.02 of the truth over the observed impact speeds
    And the JSON names the flight law and both impact-law formulas

    Examples:
      | right            | left           |
      | linear:0.95:0.12 | power:0.9:0.2  |
      | power:0.15:0.5   | 0.3            |

  Scenario: A missing recording is refused
    Given recordings simulated at 6, 7.5 and 9 mm with right wall "0.88" and left wall "0.3"
    When I run discover on them and a file that does not exist
    Then I get one line that names the missing file
    And no output directory is written
