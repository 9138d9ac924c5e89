"""A real Dask cluster on loopback for the tests and benchmarks: a ``dask scheduler`` and
single-thread ``dask worker`` processes started from the command line, as a user would."""

from __future__ import annotations

import contextlib
import os
import shutil
import socket
import subprocess
import sys
import tempfile


def dask_command() -> str | None:
    """The ``dask`` command of this interpreter's environment (None if not installed)."""
    return shutil.which("dask", path=os.path.dirname(sys.executable)) or shutil.which("dask")


@contextlib.contextmanager
def command_line_cluster(workers: int = 2, log_dir: str | None = None):
    """Start a scheduler and ``workers`` worker processes; yield the scheduler address.

    Output goes to ``log_dir`` (``s.log``, ``w0.log``, ...) or is discarded. The processes
    are terminated on exit (killed after 20 s).
    """
    import distributed

    exe = dask_command()
    if exe is None:
        raise RuntimeError("the dask command line is not installed (pip install -e '.[dask]')")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    with tempfile.TemporaryDirectory() as scratch:
        def out(name):
            return open(os.path.join(log_dir, name), "w") if log_dir else subprocess.DEVNULL

        procs = [subprocess.Popen([exe, "scheduler", "--host", "127.0.0.1", "--port",
                                   str(port), "--dashboard-address", ":0", "--no-show"],
                                  stdout=out("s.log"), stderr=subprocess.STDOUT, env=env)]
        try:
            for k in range(workers):
                procs.append(subprocess.Popen(
                    [exe, "worker", address, "--nthreads", "1", "--nworkers", "1",
                     "--no-dashboard", "--local-directory", os.path.join(scratch, f"w{k}")],
                    stdout=out(f"w{k}.log"), stderr=subprocess.STDOUT, env=env))
            with distributed.Client(address, timeout="60s") as c:
                c.wait_for_workers(workers, timeout=120)
            yield address
        finally:
            for p in procs[::-1]:
                p.terminate()
            for p in procs:
                try:
                    p.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    p.kill()
