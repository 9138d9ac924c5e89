Feature: Classify the regime of a recording
  As a researcher with recordings of a rig I want each one labelled with its
  vibro-impact regime and the probability of every label, computed from the
  sensor data alone, and a warning when a recording is unlike anything the
  classifier was trained on.

  Scenario: Classifying simulated recordings of the paper's rig
    Given recordings of the paper's rig simulated at 9 and 17.5 mm
    When I run "vidiscover classify" on them with --json
    Then the command succeeds
    And I get one entry per file with a label and the probability of every label
    And each label is the regime the simulation went through

  Scenario: A recording outside the training domain is flagged
    Given a recording simulated with a half-clearance of 60 mm
    When I run "vidiscover classify" on it with --json
    Then the command succeeds
    And a warning on stderr says the recording is outside the training domain

  Scenario: A missing recording is a one-line error
    When I run "vidiscover classify" on a file that does not exist
    Then the command fails with exit status 2 and one line on stderr

  Scenario: Training a small classifier from a seed
    When I run "vidiscover train --seed 3 --n 16 --n-test 10 --n-jobs 1" with --json
    Then the command succeeds
    And the JSON reports balanced_accuracy and confusion
    And the model file and its training report are written
    And the model file loads with the trusted types only and labels a recording

  Scenario: Training refuses a model path it cannot write
    When I run "vidiscover train --out model.pkl"
    Then the command fails with exit status 2 and one line on stderr
