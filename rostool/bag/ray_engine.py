"""Bags on Ray: the same per-bag work as `many.run`, as Ray tasks, on a private local Ray or a cluster.

Without an address (`--ray-address`, else RAY_ADDRESS) a local Ray is started for the run and stopped after
it: loopback only (Ray 2.60 binds its daemons to every interface unless RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0),
no dashboard, no usage statistics, workers at the user's priority (Ray's default is nice 15), and token
authentication with a token of this run's own, kept in the environment (a plain `ray.init()` would write
~/.ray/auth_token, which later clients then trip over). With an address, the cluster's own settings hold
(its workers' niceness too); rostool must be installed on its nodes. Ray's log lines stay out
of the user's terminal: failures come back as rostool's one-line errors.
"""

from __future__ import annotations

import logging
import os
import secrets
import socket
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any, TypeVar

from rostool.bag.many import BagItem, Failure, Results, Work, call
from rostool.errors import RostoolError

T = TypeVar("T")
RAY_HINT = "pip install 'rostool[ray]'"


def connect(address: str | None) -> Any:
    """The `ray` module, connected: to Ray already connected in this process, else to the cluster at
    `address` (or RAY_ADDRESS), else to a private local Ray started now (see the module's docstring)."""
    address = address or os.environ.get("RAY_ADDRESS") or None
    # before Ray is imported: it reads its settings once
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    if not address or _is_loopback(address):  # else Ray swaps 127.0.0.1 for this machine's public address
        os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = "0"
    if not address and "RAY_AUTH_MODE" not in os.environ:
        os.environ["RAY_AUTH_MODE"] = "token"
        os.environ["RAY_AUTH_TOKEN"] = secrets.token_hex(32)
    try:
        import ray
    except ImportError as err:
        raise RostoolError(f"the ray module is not installed: {RAY_HINT}") from err
    if ray.is_initialized():
        return ray
    if address:
        _reachable(address)
    quiet: dict[str, Any] = {"logging_level": logging.ERROR, "log_to_driver": False}
    try:
        if address:
            ray.init(address=address, **quiet)
        else:
            # Ray runs its workers at nice 15: on a machine doing other work, a private Ray's export would
            # yield to everything else, where the local engine's processes do not
            ray.init(
                include_dashboard=False,
                _node_ip_address="127.0.0.1",
                _system_config={"worker_niceness": 0},
                **quiet,
            )
    except Exception as err:  # Ray's own errors: a wrong address, a cluster that does not answer
        where = f"the Ray cluster at {address}" if address else "a local Ray"
        raise RostoolError(f"cannot start {where}: {_first_line(err)}") from err
    return ray


@contextmanager
def session(address: str | None) -> Iterator[Any]:
    """`connect`, for one command: Ray is shut down (a private one stopped) at the end."""
    ray = connect(address)
    try:
        yield ray
    finally:
        ray.shutdown()


def runner(address: str | None) -> Callable[..., Results[Any]]:
    """A `many.run` look-alike whose bags are Ray tasks (Ray spreads and reports them: the local
    engine's jobs, label and progress bar do not apply)."""

    def run(func: Work[T], items: Sequence[BagItem], *_local: object) -> Results[T]:
        with session(address) as ray:
            task = ray.remote(num_cpus=1, max_retries=0)(call)
            refs = [task.remote(func, item) for item in items]
            done = 0
            try:
                for item, ref in zip(items, refs, strict=True):
                    try:
                        result: T | Failure = ray.get(ref)
                    except ray.exceptions.RayError as err:  # the task's process died, or Ray failed
                        result = Failure(f"{item.path}: {_first_line(err)}")
                    done += 1
                    yield item, result
            except BaseException:  # Ctrl+C, or a failure that ends the command: the rest is not wanted
                for ref in refs[done:]:
                    ray.cancel(ref, force=True)
                raise

    return run


def _reachable(address: str) -> None:
    """A one-line error now for a cluster nothing answers at: Ray would retry for minutes, printing its own
    log lines on stderr."""
    host, _, port = address.rpartition(":")
    if "://" in address or not port.isdigit():
        return  # ray://... (Ray Client) and the like: Ray's own checks
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=10):
            pass
    except OSError as err:
        raise RostoolError(f"cannot reach the Ray cluster at {address}: {err.strerror or err}") from err


def _is_loopback(address: str) -> bool:
    host = address.rpartition(":")[0].strip("[]") if ":" in address else address
    return host in ("localhost", "::1") or host.startswith("127.")


def _first_line(err: BaseException) -> str:
    text = str(err).strip() or type(err).__name__
    return text.splitlines()[0]
