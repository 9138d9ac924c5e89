"""``vidiscover orbits`` and ``vidiscover continue``: JSON keys, outputs, bad input."""

import json

from click.testing import CliRunner

from vidiscover.cli import main


def _run(args):
    return CliRunner().invoke(main, args, catch_exceptions=False)


def test_orbits_json_has_the_contract_keys():
    res = _run(["orbits", "--preset", "paper", "--b", "0.012", "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.output)
    assert len(doc["orbits"]) == 2
    kinds = {(o["kind"], o["stable"]) for o in doc["orbits"]}
    assert kinds == {("2ipc_sym", True), ("2ipc_sym", False)}
    for o in doc["orbits"]:
        assert {"kind", "impacts_per_period", "period_cycles", "stable", "multipliers",
                "impacts"} <= set(o)
        assert o["impacts_per_period"] == 2 and o["period_cycles"] == 1
        assert len(o["multipliers"]) == 4
        assert [i["side"] for i in sorted(o["impacts"], key=lambda i: i["t"])] in (
            ["right", "left"], ["left", "right"])
        for i in o["impacts"]:
            assert 0 <= i["t"] < 0.125 and (i["v"] > 0) == (i["side"] == "right")


def test_orbits_not_found_is_a_result_with_the_reason():
    res = _run(["orbits", "--b", "0.012", "--effect", "coulomb_friction=1.0", "--json"])
    assert res.exit_code == 0
    doc = json.loads(res.output)
    assert doc["orbits"] == [] and not doc["found"] and "no periodic" in doc["reason"]


def test_continue_writes_outputs_and_reports_the_period_doubling(tmp_path):
    out = tmp_path / "cont"
    res = _run(["continue", "--param", "b", "--from", "0.009", "--to", "0.007",
                "--out", str(out), "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.output)
    assert doc["branches"] and all({"kind", "points"} <= set(b) for b in doc["branches"])
    pt = doc["branches"][0]["points"][0]
    assert {"value", "stable", "max_multiplier"} <= set(pt)
    pds = [b for b in doc["bifurcations"] if b["type"] == "period_doubling"]
    assert pds and abs(pds[0]["value"] - 0.00767) < 1e-5
    for f in doc["outputs"]:
        assert (tmp_path / "cont" / f.split("cont/", 1)[1]).is_file()
    assert json.loads((out / "continuation.json").read_text())["bifurcations"]


def test_bad_input_exits_2_with_one_line(tmp_path):
    cases = [
        ["continue", "--param", "nonsense", "--from", "1", "--to", "2", "--out",
         str(tmp_path / "a")],
        ["continue", "--param", "b", "--from", "0.01", "--to", "0.01", "--out",
         str(tmp_path / "b")],
        ["orbits", "--b", "-0.01"],
        ["orbits", "--effect", "restitution_drift"],
    ]
    for args in cases:
        res = CliRunner().invoke(main, args)
        assert res.exit_code == 2, (args, res.output)
        assert len(res.output.strip().splitlines()) == 1, res.output
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_sweep_overlays_the_continued_branches(tmp_path):
    """``sweep --overlay-branches``: branches.json beside the diagram; the stable
    symmetric two-impact branch covers the sweep's 2ipc_sym points."""
    out = tmp_path / "sw"
    res = _run(["sweep", "--param", "b", "--from", "0.011", "--to", "0.012", "--n", "3",
                "--n-jobs", "1", "--duration", "1", "--overlay-branches",
                "--out", str(out), "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.output)
    assert str(out / "branches.json") in doc["outputs"]
    assert (out / "bifurcation.png").stat().st_size > 0
    saved = json.loads((out / "branches.json").read_text())["branches"]
    assert len(saved) == len(doc["branches"]) >= 1
    sym = [b for b in saved if b["kind"] == "2ipc_sym"
           and any(p["stable"] for p in b["points"])]
    assert sym, [b["kind"] for b in saved]
    values = [p["value"] for p in sym[0]["points"] if p["stable"]]
    assert min(values) <= 0.011 + 1e-6 and max(values) >= 0.012 - 1e-6
    assert set(doc["labels"]) == {"2ipc_sym"}


def test_sweep_overlay_refuses_the_noise_parameter(tmp_path):
    res = CliRunner().invoke(main, ["sweep", "--param", "noise", "--from", "0.5", "--to", "1",
                                    "--n", "2", "--overlay-branches", "--out",
                                    str(tmp_path / "n")])
    assert res.exit_code == 2 and "noise" in res.output
    assert len(res.output.strip().splitlines()) == 1
    assert not (tmp_path / "n").exists()
