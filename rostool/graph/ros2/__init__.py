"""ROS 2 live graph spoken directly over DDS (Eclipse Cyclone DDS's Python binding), no rclpy.

`dds.py` participant, configuration and QoS; `names.py` ROS <-> DDS names; `types.py` message types and
their DDS registration; `discovery.py` the graph cache; `graph.py` the Graph the verbs use.
"""
