"""The DDS transport of the ROS 2 graph (`graph/ros2_base/`): Eclipse Cyclone DDS's Python binding, no rclpy.

`dds.py` participant and Cyclone configuration; `session.py` the participant with its announced node,
readers and writers; `discovery.py` the graph cache; `types.py` message types and their DDS registration;
`services.py` and `actions.py` rmw's request/reply and action conventions; `type_description.py` REP 2016;
`graph.py` the transport methods of `Ros2Base`.
"""
