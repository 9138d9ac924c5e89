"""The console script leaves a finished command without the interpreter's teardown.

:func:`vidiscover.cli._leave`: exit handlers run and the streams are flushed, then the
process ends with the command's status (the teardown of numpy/pandas/scipy/sklearn
takes 0.3-0.9 s and changes nothing).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    import atexit, sys
    from vidiscover import cli

    class Teardown:
        def __del__(self):
            print("teardown ran", flush=True)

    kept = Teardown()                      # finalised only by the interpreter's teardown
    atexit.register(print, "exit handler ran")
    sys.argv = ["vidiscover", *sys.argv[1:]]
    print("partial line without newline", end="")
    cli.entry()
""")


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", SCRIPT, *args], capture_output=True,
                          text=True, timeout=120)


def test_a_finished_command_runs_exit_handlers_flushes_and_skips_the_teardown():
    done = _run("--version")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("partial line without newline")
    assert "version" in done.stdout                       # the command's own output
    assert done.stdout.rstrip().endswith("exit handler ran")
    assert "teardown ran" not in done.stdout


def test_the_exit_status_of_a_failed_command_is_kept():
    done = _run("--no-such-option")
    assert done.returncode == 2
    assert "exit handler ran" in done.stdout
    assert "teardown ran" not in done.stdout


def test_a_running_non_daemon_thread_gets_the_usual_exit():
    script = SCRIPT.replace(
        "cli.entry()",
        "import threading, time\n"
        "threading.Thread(target=time.sleep, args=(0.5,)).start()\n"
        "cli.entry()")
    done = subprocess.run([sys.executable, "-c", script, "--version"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "teardown ran" in done.stdout
