"""The graph daemon under churn (issue 21): nodes that live only a few seconds are still named, and none is
listed after it left.

A Fast DDS participant sends its ros_discovery_info sample to a reader as soon as it learns of it, usually
before the daemon's participant has learnt of its writer (Fast DDS describes its endpoints about 1 s after
meeting a participant), so the first sample is dropped and the next comes with the writer's heartbeat, 3 s
later: a node living about that long was often never named. The DDS graph now makes a new reader once such a
writer is known (discovery.py, `GraphCache._prompt_newcomers`), which the writer answers at once.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

from tests.ros2_peers import BRIEF_NODE, RclpyPeer, WarmDaemon, peer_env, peer_python, serving
from tests.support import rostool, wait_until

# Each brief node lives LIFE seconds from its context's start: longer than the daemon needs to learn its
# endpoints and ask (about 1.2 s), shorter than the first heartbeat of its ros_discovery_info writer (3 s),
# which was the only way its name came before.
LIFE = 2.5
BRIEF = 4


def _ask(daemon: WarmDaemon, method: str) -> Any:
    """A query on the daemon's socket from this process (a `rostool node list` per poll would cost a
    Python start-up each)."""
    from rostool.graph.daemon.client import DaemonClient
    from rostool.graph.daemon.place import DaemonPlace

    (path,) = daemon.run_dir.glob("rostool/*.sock")
    place = DaemonPlace(path.stem, path, path.with_suffix(".lock"), path.with_suffix(".log"), ())
    return DaemonClient("auto", daemon.env, place).query(method, [])


def _named_while_alive(daemon: WarmDaemon, python: Path, env: dict[str, str], name: str) -> bool:
    brief = subprocess.Popen([str(python), "-c", BRIEF_NODE, name, str(LIFE)], env=env, text=True,
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)  # fmt: skip
    try:
        assert brief.stdout is not None and brief.stdout.readline().strip() == "up"
        while brief.poll() is None:
            if f"/{name}" in _ask(daemon, "node_names"):
                return True
        return False
    finally:
        brief.communicate(timeout=30)


def test_brief_nodes_are_named_while_alive_and_gone_after(
    distro: str, graph_env: dict[str, str], tmp_path: Path
) -> None:
    env = {**graph_env, "ROSTOOL_DAEMON_BUILD": "test-churn"}  # edits to the checkout do not replace it
    python, fast = peer_python(distro), peer_env(graph_env, tmp_path)
    with serving(env) as daemon:
        steady = RclpyPeer(distro, env, tmp_path, ["--name", "steady", "--talk", "/steady"])
        try:
            steady.wait_for("ready", timeout=30)
            daemon.ready()
            assert wait_until(lambda: "/steady" in _ask(daemon, "node_names"), timeout=30)
            named = [k for k in range(BRIEF) if _named_while_alive(daemon, python, fast, f"brief_{k}")]
            assert named == list(range(BRIEF)), f"named while alive: {named} of {BRIEF}"
            # a reader made for a newcomer brings the leavers' last samples too: none comes back
            assert wait_until(lambda: _ask(daemon, "node_names") == ["/steady"], timeout=30)
        finally:
            steady.stop()


def test_status_reports_the_daemons_memory(graph_env: dict[str, str]) -> None:
    """`daemon status --json` gives the resident set (as /proc reads it) and malloc's bytes in use, which
    tell a leak from the allocator's fragmentation under churn (bench/bench_daemon_rss.py)."""
    with serving(graph_env) as daemon:
        daemon.ready()
        done = rostool(["--ros2", "daemon", "status", "--json"], daemon.env)
        assert done.returncode == 0, done.stderr
        found = json.loads(done.stdout)
        with open(f"/proc/{found['pid']}/status", encoding="utf-8") as status:
            (rss,) = [int(line.split()[1]) for line in status if line.startswith("VmRSS:")]
        memory = found["memory"]
        assert 0.5 * rss < memory["rss_kib"] < 2 * rss
        assert 0 < memory["malloc_in_use_kib"] < memory["rss_kib"]


# Run in a process of its own, so the test worker's other threads do not move malloc's count.
QOS_COPIES = r"""
import gc, json
from cyclonedds.qos import Policy, Qos, _CQos
from rostool.graph.daemon.memory import memory
from rostool.graph.ros2.dds import free_qos_copies
free_qos_copies()
user, topic, group = b"typehash=RIHS01_" + b"0" * 64 + b";", b"t" * 40, b"g" * 40
cqos = _CQos.qos_to_cqos(Qos(Policy.Userdata(data=user), Policy.Topicdata(data=topic),
                             Policy.Groupdata(data=group)))
back = _CQos.cqos_to_qos(cqos)
read = [back[Policy.Userdata].data.decode(), back[Policy.Topicdata].data.decode(),
        back[Policy.Groupdata].data.decode()]
for _ in range(1000):
    _CQos.cqos_to_qos(cqos)
gc.collect()
before = memory()["malloc_in_use_kib"]
for _ in range(20000):
    _CQos.cqos_to_qos(cqos)
gc.collect()
print(json.dumps({"read": read, "grew_kib": memory()["malloc_in_use_kib"] - before}))
"""


def test_reading_a_qos_keeps_no_copy_of_its_data() -> None:
    """Every discovered endpoint's QoS is read with its USER_DATA (cyclonedds-python leaked each copy: ~2 KiB
    per participant that came and went, the daemon's slow growth under churn): the data read back is the
    data written, and 20,000 reads leave malloc's count where it was (the library's own getters: +4.3 MiB)."""
    done = subprocess.run([sys.executable, "-c", QOS_COPIES], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    found = json.loads(done.stdout)
    assert found["read"] == ["typehash=RIHS01_" + "0" * 64 + ";", "t" * 40, "g" * 40]
    assert found["grew_kib"] < 256, found
