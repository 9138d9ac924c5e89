Feature: Diagnose the sim-to-real gap
  As a researcher whose rig does not behave like the paper's model, I want to know
  where the model and the measurement differ, which unmodelled effect explains it,
  and how much of the difference is left unexplained.

  Scenario: A withheld effect is found, fitted and removes the gap
    Given a recording simulated at 9 mm with the withheld effect "excitation_distortion=0.06,0.5"
    When I run vidiscover gap on it with --json
    Then the JSON document has the keys gap_before, effects, attributed and unexplained
    And the attributed effect is "excitation_distortion"
    And the attributed effect removes at least 60 % of the gap
    And the output directory holds summary.json, report.html and the waterfall figure

  Scenario: A missing recording is one line on stderr and no output
    When I run vidiscover gap on a file that does not exist
    Then the command exits with status 2 and one line naming the file
    And no output directory is left behind

  Scenario: The withheld-effect battery reports accuracy and a confusion table
    When I run the quick withheld-effect battery
    Then every case has an expected and a predicted verdict
    And the no-effect case is reported as no significant gap
    And the out-of-catalogue case leaves at least half of the gap unexplained
