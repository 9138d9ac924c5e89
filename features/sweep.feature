Feature: Parameter sweeps and bifurcation diagrams
  As a researcher doing an experimental bifurcation analysis of the rig, I want to
  sweep one parameter, get the regime and the impact time differences at every
  value in a table and a bifurcation diagram, and run the same sweep on my
  workstation or on a Dask cluster with the same results.

  Scenario: Sweeping the clearance
    Given the paper preset
    When I sweep "b" from 4 mm to 20 mm in 5 points
    Then every point has a ground-truth regime label
    And at 20 mm the ball hits both walls alternately, half a period apart
    And the number of detected impacts matches the truth at every point

  Scenario: The backend does not change the results
    Given the paper preset
    When I sweep "b" from 5 mm to 15 mm in 3 points serially
    And I run the same sweep on a local Dask cluster
    Then the two tables are identical

  Scenario: Sweeping an effect parameter
    Given the paper preset with a half-clearance of 15 mm
    When I sweep "r" from 0.6 to 0.9 in 3 points
    Then the restitution estimated from the sensor data follows the swept value

  Scenario: The command writes the table and the diagram
    When I run "vidiscover sweep --param b --from 0.008 --to 0.016 --n 3 --n-jobs 1 --settle 3 --duration 1.5 --out sw --json"
    Then the JSON lists 3 rows and the outputs
    And "sw" holds sweep.parquet, bifurcation.parquet, sweep.json and bifurcation.png

  Scenario: An unknown parameter is refused with one line
    When I run "vidiscover sweep --param clearance --from 0.005 --to 0.01 --n 3 --out sw"
    Then the command fails with status 2
    And the error message says "unknown parameter"
    And no file is written
