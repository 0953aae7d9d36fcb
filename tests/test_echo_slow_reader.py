"""`topic echo` into a pipe nobody reads, of 1 MB messages at 50 Hz from a real rospy publisher: memory
stays bounded (a byte budget, the oldest dropped with a counted warning, as rostopic's queue drops)."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

from tests.support import debian_popen, stop, wait_until

PUBLISHER = """
import rospy
from std_msgs.msg import String
rospy.init_node("big_talker")
pub = rospy.Publisher("/big", String, queue_size=10)
rate = rospy.Rate(50)
data = "x" * 1000000
while not rospy.is_shutdown():
    pub.publish(String(data=data))
    rate.sleep()
"""


def _rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def test_echo_into_an_unread_pipe_stays_bounded(debian_master: dict[str, str], tmp_path: Path) -> None:
    env = debian_master
    script = tmp_path / "big_talker.py"
    script.write_text(PUBLISHER)
    publisher = debian_popen(["/usr/bin/python3", str(script)], env)
    errors = (tmp_path / "stderr").open("w+")
    echo = subprocess.Popen(  # stdout is a pipe this test never reads: echo blocks once it is full
        [sys.executable, "-m", "rostool", "--ros1", "topic", "echo", "/big"],
        env=env, stdout=subprocess.PIPE, stderr=errors, text=True,
    )  # fmt: skip
    try:
        assert wait_until(lambda: "dropped" in (tmp_path / "stderr").read_text(), 60), (
            tmp_path / "stderr"
        ).read_text()
        peak = 0.0
        deadline = time.monotonic() + 8
        while time.monotonic() < deadline:  # 8 s more at 50 MB/s: 400 MB would have piled up
            peak = max(peak, _rss_mb(echo.pid))
            time.sleep(0.2)
        assert echo.poll() is None
    finally:
        echo.kill()
        echo.wait(10)
        stop(publisher)
        errors.close()
    assert peak < 300, f"echo's memory grew to {peak:.0f} MB"
    warning = [line for line in (tmp_path / "stderr").read_text().splitlines() if "dropped" in line]
    assert warning[0].startswith("rostool: warning: dropped "), warning
