#!/usr/bin/env bash
# Runs the whole test suite. Installs what the tests need: rostool with its test extras in ./.venv; when
# missing and running as root, Debian's real ROS 1 tools (the peers every ROS 1 test talks to); and the real
# ROS 2 peers (rclpy of Jazzy and Kilted with Fast DDS), each in its own cached venv.
set -euo pipefail
cd "$(dirname "$0")"
# The suite starts thousands of Python processes importing the same modules: let them keep bytecode
# (rostool's __pycache__, pytest's rewritten test modules) even where the caller's environment turns that
# off (PYTHONDONTWRITEBYTECODE=1, as some containers set): else every rostool run compiles the modules it
# imports (~25 ms of CPU) and every xdist worker compiles the tests (~2.4 s) (CONTRIBUTING, "Test suite timing")
unset PYTHONDONTWRITEBYTECODE

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

# The real ROS 2 peers: rclpy with Fast DDS (rmw_fastrtps_cpp) and the message packages the tests use, one
# venv per distro, cached outside the repo (ROSTOOL_PEERS_DIR) and reinstalled only when this list changes.
export ROSTOOL_PEERS_DIR="${ROSTOOL_PEERS_DIR:-$HOME/.cache/rostool/peers}"
rostool_stamp() { echo "$(pwd) $(md5sum pyproject.toml)"; }  # an editable rostool is current while this holds
ros2_messages=(std-msgs std-srvs test-msgs geometry-msgs sensor-msgs nav-msgs lifecycle-msgs rcl-interfaces
  action-msgs ament-index-python)
for distro in jazzy kilted; do
  peer_packages=("ros-$distro-rclpy" "ros-$distro-rmw-fastrtps-cpp" "${ros2_messages[@]/#/ros-$distro-}")
  venv="$ROSTOOL_PEERS_DIR/$distro"
  if [ "$(cat "$venv/.installed" 2>/dev/null)" != "${peer_packages[*]}" ]; then
    echo "test.sh: installing the $distro rclpy peers into $venv"
    rm -rf "$venv"
    python3 -m venv "$venv"
    "$venv/bin/python" -m pip install -q --disable-pip-version-check "${peer_packages[@]}"
    echo "${peer_packages[*]}" > "$venv/.installed"
  fi
  # rostool itself (editable, with its dependencies) for the rclpy backend's tests: again when the checkout
  # moved or pyproject.toml (the dependencies, the entry point) changed
  if [ "$(cat "$venv/.rostool" 2>/dev/null)" != "$(rostool_stamp)" ]; then
    "$venv/bin/python" -m pip install -q --disable-pip-version-check -e .
    rostool_stamp > "$venv/.rostool"
  fi
done

# The real `ros2` (ros2cli of Jazzy, pure Python, not on pip) beside the Jazzy peers, as the referee of rostool's
# ROS 2 output (../shared/referees/README.md). Reinstalled when its source changes; built from a copy, since
# pip builds in the source tree and shared/ may be read-only.
ros2cli_src="$(cd .. && pwd)/shared/referees/ros2cli-jazzy"
jazzy_venv="$ROSTOOL_PEERS_DIR/jazzy"
if [ -d "$ros2cli_src" ]; then
  ros2cli_stamp="$(cd "$ros2cli_src" && find . -type f | sort | xargs md5sum | md5sum | cut -d' ' -f1)"
  if [ "$(cat "$jazzy_venv/.ros2cli" 2>/dev/null)" != "$ros2cli_stamp" ]; then
    echo "test.sh: installing the real ros2 (ros2cli Jazzy) into $jazzy_venv"
    build_dir="$(mktemp -d)"
    cp -r "$ros2cli_src"/. "$build_dir"
    chmod -R u+w "$build_dir"
    "$jazzy_venv/bin/python" -m pip install -q --disable-pip-version-check \
      argcomplete packaging psutil pyyaml numpy setuptools wheel
    (cd "$build_dir" && "$jazzy_venv/bin/python" -m pip install -q --disable-pip-version-check --no-deps \
      --no-build-isolation ./rosidl_runtime_py ./ros2cli ./ros2node ./ros2service ./ros2topic ./ros2param \
      ./ros2action ./ros2interface ./ros2lifecycle)
    rm -rf "$build_dir"
    echo "$ros2cli_stamp" > "$jazzy_venv/.ros2cli"
  fi
elif [ -n "${CI:-}" ]; then
  echo "test.sh: $ros2cli_src is missing: the real ros2 (the referee of the ROS 2 output) cannot be installed" >&2
  exit 1
fi

# ./.venv: rostool (editable) with its test extras, 1.3 GB of wheels that take pip 80-90 s to install. A
# copy of a current one is kept beside the peers (test-venv, stamped with pyproject.toml): a fresh clone
# copies it (~6 s), then pip points its editable rostool at the clone (~4 s, every dependency present).
# The copy's console scripts (ray, moto_server: tests run them) get this venv's python on their #! line.
test_venv="$ROSTOOL_PEERS_DIR/../test-venv"
deps_stamp() { echo "$(python3 --version) $(md5sum pyproject.toml)"; }  # what the test venv holds
if [ ! -x .venv/bin/python ]; then
  if [ "$(cat "$test_venv/.deps" 2>/dev/null)" = "$(deps_stamp)" ]; then
    echo "test.sh: copying the test venv from $test_venv"
    cp -a "$test_venv" .venv
    grep -lIs '^#!.*/bin/python' .venv/bin/* | xargs -r sed -i "1s|^#!.*/bin/python[0-9.]*\$|#!$PWD/.venv/bin/python|" || true
  else
    python3 -m venv .venv
  fi
fi
if [ "$(cat .venv/.rostool 2>/dev/null)" != "$(rostool_stamp)" ]; then
  .venv/bin/python -m pip install -q --disable-pip-version-check -e '.[test]'
  rostool_stamp > .venv/.rostool
fi
if [ "$(cat "$test_venv/.deps" 2>/dev/null)" != "$(deps_stamp)" ]; then
  # written whole under another name, then renamed: a test.sh copying it meanwhile never sees half of it
  rm -rf "$test_venv.$$" "$test_venv.old.$$"
  cp -a .venv "$test_venv.$$"
  deps_stamp > "$test_venv.$$/.deps"
  if [ -e "$test_venv" ]; then mv -T "$test_venv" "$test_venv.old.$$"; fi
  mv -T "$test_venv.$$" "$test_venv" && rm -rf "$test_venv.old.$$"
fi
.venv/bin/python -m ruff check rostool tests bench
# pytest-xdist: the suite mostly waits (DDS discovery, peers starting), so more workers than cores pay off
# (CONTRIBUTING.md, "Test suite timing": -n 5 ran a fresh clone in 822 s where -n 4 took 929 s); loadgroup
# would keep xdist_group-marked tests on one worker, but groups nothing with pytest 9.2 (pytest-xdist #1386).
# Arguments given to test.sh come last and win (`./test.sh -n 0 tests/test_cli.py`).
# --reruns: a stopgap while real-peer discovery under a loaded 2-core machine can still miss a participant
# (issue 23): a test passes only if one of its three runs passes whole; every rerun is listed in the summary.
exec .venv/bin/python -m pytest -q -n 5 --dist loadgroup --reruns 2 --reruns-delay 1 -r R "$@"
