"""Parameter sweeps: parameter resolution, seeds, rows against a direct run, outputs."""

import json
import pickle

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from vidiscover import Effects, preset
from vidiscover.errors import InputError
from vidiscover.regimes.labels import LABELS, label_simulation
from vidiscover.sweep import (
    SweepSpec,
    bifurcation_table,
    plot_bifurcation,
    resolve_param,
    sweep,
    sweep_params,
    write_sweep,
)

FAST = dict(settle=3.0, duration=1.5, n_jobs=1, progress=False)


@pytest.fixture(scope="module")
def b_sweep():
    """A small serial b sweep shared by several tests (real simulations)."""
    return sweep("b", [0.004, 0.009, 0.015, 0.02], seed=3, settle=10.0, duration=2.0,
                 n_jobs=1, progress=False)


# ------------------------------------------------------------------ parameters
@pytest.mark.parametrize("name, expected", [
    ("b", ("params", None, "b")),
    ("amplitude", ("params", None, "amplitude")),
    ("r", ("params", None, "r")),
    ("noise", ("noise", None, "noise")),
    ("mu", ("effect", "coulomb_friction", "mu")),
    ("coulomb_friction.mu", ("effect", "coulomb_friction", "mu")),
    ("theta", ("effect", "inclination", "theta")),
    ("inclination.theta", ("effect", "inclination", "theta")),
    ("r_left", ("effect", "asymmetric_restitution", "r_left")),
])
def test_resolve_param(name, expected):
    assert resolve_param(name) == expected


def test_every_listed_parameter_resolves():
    for name in sweep_params():
        resolve_param(name)


@pytest.mark.parametrize("name, match", [
    ("foo", r"--param 'foo': unknown parameter; sweepable parameters: m1"),
    ("velocity_dependent_restitution.right", "not a numeric effect parameter"),
    ("inclination.mu", "not a numeric effect parameter"),
])
def test_unknown_parameter_is_an_input_error(name, match):
    with pytest.raises(InputError, match=match):
        resolve_param(name)


def test_configure_sets_a_field_an_effect_parameter_or_the_noise():
    spec = SweepSpec("mu", (0.2,), base=preset("paper", b=0.015),
                     effects=Effects.parse(["inclination=2", "coulomb_friction=0.05"]))
    params, fx, noise = spec.configure(0.2)
    assert params == preset("paper", b=0.015) and noise == 1.0
    assert fx.to_dict() == {"inclination": {"theta": 2.0}, "coulomb_friction": {"mu": 0.2}}
    spec = SweepSpec("asymmetric_restitution.r_left", (0.3,))
    assert spec.configure(0.3)[1].to_dict() == {
        "asymmetric_restitution": {"r_right": 0.8782, "r_left": 0.3}}  # default r_right kept
    assert SweepSpec("b", (0.01,)).configure(0.01)[0].b == 0.01
    assert SweepSpec("noise", (2.5,)).configure(2.5)[2] == 2.5


@pytest.mark.parametrize("param, values, match", [
    ("b", [0.01, -0.001], r"sweep of b at -0.001: b must be > 0"),
    ("mu", [0.1, 3.0], r"sweep of mu at 3: effect coulomb_friction: mu must be in"),
    ("noise", [-1.0], r"sweep of noise at -1: noise must be >= 0"),
    ("b", [], "sweep values are empty"),
    ("b", [0.01, float("nan")], "sweep values must be finite, got nan"),
    ("b", ["x"], "sweep values must be numbers"),
])
def test_bad_values_fail_before_any_work(param, values, match):
    with pytest.raises(InputError, match=match):
        sweep(param, values, **FAST)


@pytest.mark.parametrize("kw, match", [
    (dict(seed=-1), "seed must be a non-negative integer, was -1"),
    (dict(n_boot=-5), "n_boot must be a non-negative integer, was -5"),
    (dict(settle=-1.0), "settle must be >= 0 s, was -1.0"),
])
def test_bad_options_are_input_errors(kw, match):
    with pytest.raises(InputError, match=match):
        SweepSpec("b", (0.01,), **kw)


def test_spec_pickles_with_its_effects():
    spec = SweepSpec("theta", (1.0, 2.0), effects=Effects.parse(["coulomb_friction=0.2"]))
    assert pickle.loads(pickle.dumps(spec)) == spec


# ------------------------------------------------------------------ seeds
def test_point_seeds_are_distinct_and_depend_only_on_seed_and_index():
    a = SweepSpec("b", tuple(np.linspace(0.005, 0.02, 50)), seed=11)
    b = SweepSpec("amplitude", (0.0004,) * 3, seed=11)
    seeds = [a.point_seed(i) for i in range(50)]
    assert len(set(seeds)) == 50
    assert [b.point_seed(i) for i in range(3)] == seeds[:3]
    assert SweepSpec("b", (0.01,), seed=12).point_seed(0) != seeds[0]


def test_rows_do_not_depend_on_the_other_points():
    short = sweep("b", [0.006, 0.012], seed=5, **FAST)
    long = sweep("b", [0.006, 0.012, 0.018], seed=5, **FAST)
    pd.testing.assert_frame_equal(long.iloc[:2], short, check_exact=True)


# ------------------------------------------------------------------ rows vs ground truth
def test_rows_match_a_direct_simulation_and_label(b_sweep):
    from vidiscover.simulation import simulate

    assert list(b_sweep["value"]) == [0.004, 0.009, 0.015, 0.02]
    assert list(b_sweep["index"]) == [0, 1, 2, 3]
    for _, row in b_sweep.iterrows():
        res = simulate(preset("paper", b=row["value"]), settle=10.0, duration=2.0)
        truth = label_simulation(res)
        assert row["label"] == truth.label in LABELS
        assert row["n_impacts_true"] == res.record_impacts().n
        assert row["ipc_true"] == truth.ipc


def test_detected_impacts_and_restitution_agree_with_the_truth(b_sweep):
    # paper preset: one constant r = 0.88 on both walls, default sensor noise
    assert (b_sweep["n_impacts"] - b_sweep["n_impacts_true"]).abs().max() <= 1
    for side in ("right", "left"):
        ok = b_sweep[f"r_n_{side}"] > 5
        assert ok.any()
        np.testing.assert_allclose(b_sweep.loc[ok, f"r_rms_{side}"], 0.88, atol=0.02)


def test_impact_time_differences_span_the_record(b_sweep):
    period = 1 / preset("paper").frequency
    for _, row in b_sweep.iterrows():
        dt = np.asarray(row["dt_T"])
        assert dt.size == max(row["n_impacts"] - 1, 0)
        assert (dt > 0).all()
        assert dt.sum() * period <= 2.0  # inside the 2 s record
    # symmetric two-impact regime at large b: half a period between impacts
    big = b_sweep[b_sweep["label"] == "2ipc_sym"]
    assert len(big)
    for dt in big["dt_T"]:
        np.testing.assert_allclose(dt, 0.5, atol=0.1)


def test_swept_restitution_is_recovered_from_the_sensor_data():
    df = sweep("r", [0.6, 0.75, 0.9], base=preset("paper", b=0.015), **FAST)
    for side in ("right", "left"):
        np.testing.assert_allclose(df[f"r_rms_{side}"], df["value"], atol=0.03)


def test_sweeping_an_effect_parameter_switches_the_effect_on():
    from vidiscover.simulation import simulate

    base = preset("paper", b=0.015)
    df = sweep("theta", [0.0, 5.0], base=base, **FAST)
    res = simulate(base, Effects.parse(["inclination=5"]), settle=3.0, duration=1.5)
    assert df.loc[1, "label"] == label_simulation(res).label
    assert df.loc[1, "n_impacts_true"] == res.record_impacts().n
    # the tilt breaks the left/right symmetry of the impact time differences
    assert df.loc[1, "asymmetry"] > df.loc[0, "asymmetry"]
    assert df.attrs["sweep"]["param"] == "theta"


def test_noise_sweep_changes_only_the_recording():
    df = sweep("noise", [0.0, 3.0], base=preset("paper", b=0.015), **FAST)
    assert df["label"].nunique() == 1 and df["n_impacts_true"].nunique() == 1
    assert df.loc[0, "r_rms_right"] != df.loc[1, "r_rms_right"]


def _label_by_ipc(result):
    return "2ipc_sym" if result.features["impacts_per_cycle"] > 1.5 else "1ipc"


def test_classifier_fills_label_pred_and_must_return_a_label():
    df = sweep("b", [0.015], classify=_label_by_ipc, **FAST)
    assert df.loc[0, "label_pred"] == "2ipc_sym"
    with pytest.raises(InputError, match="classify must return a label string"):
        sweep("b", [0.015], classify=lambda result: 3, **FAST)


# ------------------------------------------------------------------ outputs
def test_bifurcation_table_is_long_and_consistent(b_sweep):
    long = bifurcation_table(b_sweep)
    assert len(long) == sum(len(d) for d in b_sweep["dt_T"])
    first = long[long["index"] == 2]
    assert (first["value"] == 0.015).all() and list(first["k"]) == list(range(len(first)))
    np.testing.assert_array_equal(first["dt_T"], b_sweep.loc[2, "dt_T"])


def test_write_sweep_round_trips_through_parquet(b_sweep, tmp_path):
    files = write_sweep(b_sweep, tmp_path / "out")
    assert all(f.is_file() and f.stat().st_size > 0 for f in files)
    points = pq.read_table(tmp_path / "out" / "sweep.parquet").to_pandas()
    pd.testing.assert_frame_equal(points, b_sweep.drop(columns=["dt_T"]), check_exact=True,
                                  check_dtype=False)
    long = pq.read_table(tmp_path / "out" / "bifurcation.parquet").to_pandas()
    pd.testing.assert_frame_equal(long, bifurcation_table(b_sweep), check_dtype=False)
    meta = json.loads((tmp_path / "out" / "sweep.json").read_text())
    assert meta["rows"] == 4 and sum(meta["labels"].values()) == 4
    assert meta["spec"]["param"] == "b"


def test_write_sweep_is_atomic(b_sweep, tmp_path, monkeypatch):
    import vidiscover.sweep as mod

    def broken(df, path=None, **kw):
        raise RuntimeError("plot failed")

    monkeypatch.setattr(mod, "plot_bifurcation", broken)
    with pytest.raises(RuntimeError, match="plot failed"):
        write_sweep(b_sweep, tmp_path / "out")
    assert list(tmp_path.iterdir()) == []


def test_plot_has_one_point_per_time_difference(b_sweep):
    fig = plot_bifurcation(b_sweep)
    top = fig.axes[0]
    n = sum(len(c.get_offsets()) for c in top.collections)
    assert n == len(bifurcation_table(b_sweep))


# ------------------------------------------------------------------ CLI
def test_cli_sweep_json_keys_and_outputs(tmp_path):
    from vidiscover.cli import main

    out = tmp_path / "sw"
    res = CliRunner().invoke(main, ["sweep", "--param", "b", "--from", "0.008", "--to",
                                    "0.016", "--n", "3", "--n-jobs", "1", "--settle", "3",
                                    "--duration", "1.5", "--out", str(out), "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert {"rows", "outputs"} <= set(doc)
    assert [r["value"] for r in doc["rows"]] == pytest.approx([0.008, 0.012, 0.016])
    assert all(r["label"] in LABELS for r in doc["rows"])
    assert sorted(doc["outputs"]) == sorted(str(p) for p in out.iterdir()
                                            if p.name != ".vidiscover")


@pytest.mark.parametrize("args, match", [
    (["--param", "nope", "--from", "0", "--to", "1", "--n", "2"], "unknown parameter"),
    (["--param", "b", "--from", "0.01", "--to", "0.02", "--n", "0"], "--n must be >= 1"),
    (["--param", "b", "--from", "0", "--to", "0.02", "--n", "2", "--log"], "--log needs"),
    (["--param", "b", "--from", "0.01", "--to", "0.02", "--n", "2", "--set", "m2"],
     "--set 'm2': expected NAME=VALUE"),
    (["--param", "b", "--from", "0.01", "--to", "0.02", "--n", "2", "--n-jobs", "0"],
     "n_jobs must be a positive integer"),
])
def test_cli_sweep_bad_input_exits_2_with_one_line(tmp_path, args, match):
    from vidiscover.cli import main

    out = tmp_path / "sw"
    res = CliRunner().invoke(main, ["sweep", *args, "--settle", "1", "--duration", "1",
                                    "--out", str(out)])
    assert res.exit_code == 2
    assert match in res.stderr and len(res.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_cli_sweep_classify_fills_predicted_labels(tmp_path):
    from vidiscover.cli import main

    res = CliRunner().invoke(main, ["sweep", "--param", "b", "--from", "0.012", "--to",
                                    "0.018", "--n", "2", "--n-jobs", "1", "--settle", "10",
                                    "--duration", "5.12", "--classify", "--out",
                                    str(tmp_path / "sw"), "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert all(r["label_pred"] in LABELS for r in doc["rows"])
    agree = [r["label_pred"] == r["label"] for r in doc["rows"]]
    assert doc["label_agreement"] == pytest.approx(sum(agree) / len(agree))


def test_regime_model_labels_in_one_batch_like_point_by_point():
    """The batched labelling of a RegimeModel equals calling it on every point."""
    from vidiscover.regimes.classifier import load_default_model
    from vidiscover.sweep import sweep

    model = load_default_model()
    values = np.linspace(0.004, 0.028, 6)
    batch = sweep("b", values, classify=model, n_jobs=1, progress=False, settle=6.0,
                  duration=2.56)
    one = sweep("b", values, classify=lambda ana: model(ana), n_jobs=1, progress=False,
                settle=6.0, duration=2.56)
    assert list(batch["label_pred"]) == list(one["label_pred"])
    assert set(batch["label_pred"]) <= set(LABELS)
