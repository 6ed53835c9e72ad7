"""A Dask cluster of separately started processes on loopback, as on a real cluster: for the
tests (tests/test_parallel.py) and benchmarks/bench_dask.py."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def separate_cluster(
    workers: int, env: dict | None = None, path=(Path(__file__).parent,), cwd=None
):
    """A Dask scheduler and `workers` single-threaded workers (no nanny), each its own
    process (`python -m distributed.cli.dask_scheduler` / `dask_worker`, as on a cluster)
    on a free loopback port, with `path` (folders: they import the job functions and
    stabctl by name, default this file's) and this process's PYTHONPATH on theirs and
    `env` added to their environment, the workers in the folder `cwd` (default this
    process's); yields (address, the scheduler's Popen, the workers' Popens) once every
    worker is in; all killed after."""
    folders = [str(p) for p in path] + list(filter(None, [os.environ.get("PYTHONPATH")]))
    env = {**os.environ, **(env or {}), "PYTHONPATH": os.pathsep.join(folders)}
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    local = ["--host", "127.0.0.1", "--no-dashboard"]
    scheduler = ["distributed.cli.dask_scheduler", "--port", str(port), *local]
    worker = ["distributed.cli.dask_worker", address, "--nthreads", "1", "--no-nanny", *local]
    procs = [
        subprocess.Popen(
            [sys.executable, "-m", *args], env=env, stderr=subprocess.DEVNULL, cwd=here
        )
        for args, here in [(scheduler, None)] + [(worker, cwd)] * workers
    ]
    try:
        yield wait_for(address, workers), procs[0], procs[1:]
    finally:
        for p in procs:
            p.kill()
            p.wait()


def wait_for(address: str, workers: int = 1, timeout: float = 60.0) -> str:
    """address once its scheduler has `workers` workers (asked through
    `stabctl.parallel.dask_client`, which closes its client however it ends: one left to
    Dask's finaliser closes in the middle of a later client's start)."""
    from stabctl.parallel import dask_client

    with dask_client(address, timeout=timeout) as client:
        client.wait_for_workers(workers, timeout=timeout)
    return address
