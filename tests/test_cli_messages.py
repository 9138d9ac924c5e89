"""Messages a new user sees: one line per error, no claims about files not written."""

from click.testing import CliRunner

from vidiscover.cli import main
from vidiscover.commands.gap import human_gap


def test_classify_on_a_directory_is_one_line(tmp_path):
    res = CliRunner().invoke(main, ["classify", str(tmp_path)])
    assert res.exit_code == 2
    assert res.stderr.count("\n") == 1
    assert "is a directory, not a recording file" in res.stderr


def test_classify_help_explains_every_label():
    from vidiscover.regimes import LABELS

    text = CliRunner().invoke(main, ["classify", "--help"]).output
    for label in LABELS:
        assert f"\n    {label} " in text, label


def test_top_level_help_does_not_truncate_descriptions():
    text = CliRunner().invoke(main, ["--help"]).output
    commands = text.split("Commands:")[1]
    assert "..." not in commands
    assert "17.5 mm" in text


def test_gap_summary_names_only_what_was_written():
    doc = {"recording": "rec", "gap_before": 3.0, "threshold": 2.0, "significant": True,
           "components": {}, "effects": [], "attributed": [], "unexplained": 1.0,
           "verdict": "unexplained", "out": "o", "files": ["summary.json", "report.html"]}
    assert "figures" not in human_gap(doc)
    doc["files"] = ["summary.json", "figures/waterfall.png", "figures/returnmap.png",
                    "report.html"]
    assert "(summary.json, figures/, report.html)" in human_gap(doc)


def test_train_refuses_an_unwritable_out_before_training(tmp_path, monkeypatch):
    import errno
    import tempfile

    def read_only(*args, **kwargs):
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(tempfile, "mkstemp", read_only)
    res = CliRunner().invoke(main, ["train", "--n", "5", "--out", str(tmp_path / "m.skops")])
    assert res.exit_code == 2
    assert "Read-only file system" in res.stderr and res.stderr.count("\n") == 1


def test_analyze_rejects_an_empty_file_before_the_heavy_imports(tmp_path):
    import subprocess
    import sys

    (tmp_path / "empty.csv").write_text("")
    code = ("import sys; from click.testing import CliRunner; from vidiscover.cli import main; "
            "r = CliRunner().invoke(main, ['analyze', 'empty.csv', '--out', 'o']); "
            "print(r.exit_code, r.stderr.strip()); "
            "print(sorted(m for m in ('sklearn', 'matplotlib', 'scipy', 'pysindy') "
            "if m in sys.modules))")
    res = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, check=True)
    status, imported = res.stdout.splitlines()
    assert status.startswith("2 ") and "empty file" in status
    assert imported == "[]"
    assert not (tmp_path / "o").exists()


def test_discover_on_a_directory_or_nothing_is_one_line(tmp_path):
    for args in (["discover", str(tmp_path), "--out", str(tmp_path / "o")],
                 ["discover", "--out", str(tmp_path / "o")]):
        res = CliRunner().invoke(main, args)
        assert res.exit_code == 2 and res.stderr.count("\n") == 1, res.output
    assert not (tmp_path / "o").exists()
