Feature: Analyze a recording of the rig
  As an experimentalist with a recording of the LO displacement, acceleration and
  base motion, I want vidiscover to find the impacts, reconstruct the ball, estimate
  the restitution coefficient of each wall and give me one report I can open and
  send, so that I get the paper's results from my own data without writing code.

  Scenario: The paper rig at b = 9 mm with one hard and one soft wall
    Given a simulated recording of the paper rig at b = 9 mm with r = 0.88 on the right wall and 0.2 on the left
    When I analyze it
    Then summary.json says there are impacts on both walls
    And summary.json gives the right wall an RMS restitution within 0.02 of 0.88
    And summary.json gives the left wall an RMS restitution within 0.02 of 0.2
    And summary.json counts as many impacts as impacts.csv has rows
    And report.html shows every figure and needs no other file

  Scenario: Two clearances in one go
    Given a simulated recording of the paper rig at b = 9 mm with r = 0.88 on the right wall and 0.2 on the left
    And a simulated recording of the paper rig at b = 15 mm with r = 0.88 on the right wall and 0.2 on the left
    When I analyze them without figures
    Then there is one report per recording
    And index.html links every report

  Scenario: A misspelled column is refused with one line
    Given a recording whose acceleration column is named "acc"
    When I analyze it
    Then the command fails with status 2
    And the error message says "missing column 'a'"
    And no output directory is written
