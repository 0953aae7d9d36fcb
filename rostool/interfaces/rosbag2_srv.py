"""rosbag2_interfaces' services as Jazzy defines them (rosbag2 0.26): the player's control services and the
recorder's snapshot, which `bag play` and `bag record --snapshot-mode` serve. Built in, so that they can
be served and called where rosbag2_interfaces is not installed."""

from __future__ import annotations

ROSBAG2_SERVICES: dict[str, str] = {
    "rosbag2_interfaces/srv/Burst": "uint64 num_messages\n---\nuint64 actually_burst\n",
    "rosbag2_interfaces/srv/GetRate": "---\nfloat64 rate\n",
    "rosbag2_interfaces/srv/IsPaused": "---\nbool paused\n",
    "rosbag2_interfaces/srv/Pause": "---\n",
    "rosbag2_interfaces/srv/PlayNext": "---\nbool success\n",
    "rosbag2_interfaces/srv/Resume": "---\n",
    "rosbag2_interfaces/srv/Seek": "builtin_interfaces/Time time\n---\nbool success\n",
    "rosbag2_interfaces/srv/SetRate": "float64 rate\n---\nbool success\n",
    "rosbag2_interfaces/srv/Snapshot": "---\nbool success\n",
    "rosbag2_interfaces/srv/SplitBagfile": "---\n",
    "rosbag2_interfaces/srv/Stop": "---\n",
    "rosbag2_interfaces/srv/TogglePaused": "---\n",
}
