"""The ROS 2 graph both ROS 2 backends share: `graph.py`'s `Ros2Base` (the Graph protocol written once)
over a transport (`transport.py`: endpoints, writers, service clients), with what it is built from: names
(ROS 2 <-> DDS), QoS and the environment, publishers, draining subscriptions, service calls, actions,
parameters and bag record's source. `graph/ros2/` (rostool's own DDS) and `graph/rclpy/` (the user's rclpy
and RMW) are transports; the graph daemon (`graph/daemon/`) serves one of them to other processes.
"""
