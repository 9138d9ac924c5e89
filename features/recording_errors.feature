Feature: Bad recordings are refused with one clear line
  As a test engineer feeding rig recordings to vidiscover, I want every bad file
  refused with a single line that names the file, says what is wrong and how to fix
  it, and leaves no half-written results behind, so that I can correct the file and
  run the analysis again.

  Background:
    Given a valid recording "rec.csv" with its metadata "rec.json"

  Scenario: A good recording is accepted
    When I analyze it
    Then it is accepted

  Scenario Outline: A bad recording is refused
    Given a recording whose <defect>
    When I analyze it
    Then I get one line that names "<file>" and says "<says>"
    And no output files are written

    Examples:
      | defect                                     | file     | says                                               |
      | column "xe" is missing                     | rec.csv  | missing column 'xe'                                |
      | column "xe" is spelled "xee"               | rec.csv  | did you mean 'xe'?                                 |
      | cell in column "x" at row 100 reads "abc"  | rec.csv  | non-numeric cell 'abc' in column 'x' at row 100    |
      | column "a" has a gap of 5 missing values   | rec.csv  | has 5 missing value(s)                             |
      | time column is not monotonic               | rec.csv  | time is not strictly increasing (non-monotonic)    |
      | time column skips a sample                 | rec.csv  | non-uniform time step                              |
      | length is only 0.5 s                       | rec.csv  | record too short: 0.5 s                            |
      | column "x" is in mm instead of m           | rec.csv  | it looks like mm, not m                            |
      | acceleration is in g instead of m/s^2      | rec.csv  | it looks like g, not m/s^2                         |
      | metadata file is missing                   | rec.csv  | create rec.json with {"b": 0.009}                  |
      | metadata says b = 0                        | rec.json | 'b' must be > 0                                    |
      | metadata says m2 = -0.032                  | rec.json | 'm2' must be > 0                                   |
      | metadata is not valid JSON                 | rec.json | malformed JSON                                     |
      | file is empty                              | rec.csv  | empty file                                         |
      | file is truncated in its last row          | rec.csv  | truncated file                                     |
      | column "a" reads 0 throughout               | rec.csv  | column 'a' is constant (0 throughout): a dead or disconnected sensor |
      | columns are in mV without sensitivities    | rec.csv  | gives no sensitivity x_mV_per_mm, a_mV_per_g, xe_mV_per_mm |
