#!/usr/bin/env bash
# Runs the whole test suite. Installs what the tests need: rostool with its test extras in ./.venv and,
# when missing and running as root, Debian's real ROS 1 tools (the peers every ROS 1 test talks to).
set -euo pipefail
cd "$(dirname "$0")"

ros_packages=(ros-core python3-rospy python3-actionlib python3-actionlib-tools python3-std-msgs
  python3-geometry-msgs python3-sensor-msgs ros-std-srvs python3-std-srvs)
if ! { command -v rosmaster && /usr/bin/python3 -c 'import rospy, actionlib, std_srvs.srv, sensor_msgs.msg'; } \
  >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    echo "test.sh: installing Debian's ROS 1 packages (the test peers)"
    apt-get update -q
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${ros_packages[@]}"
  else
    echo "test.sh: Debian's ROS 1 packages are missing and this is not root; ROS 1 tests will be skipped" >&2
  fi
fi

if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
.venv/bin/python -m pip install -q --disable-pip-version-check -e '.[test]'
.venv/bin/python -m ruff check rostool tests bench
exec .venv/bin/python -m pytest -q "$@"
