"""The rclpy transport of the ROS 2 graph (`graph/ros2_base/`): the user's own client library and middleware.

`select.py` decides between this backend and the DDS one without importing rclpy (and says why);
`facts.py` what `rostool doctor` reports; `context.py` the rclpy context, node and executor thread;
`graph.py` the transport methods of `Ros2Base`; `host.py` what its parts ask of it; `types.py` message
classes rclpy imports and their rosbags twins; `qos.py` QoS between rostool's profiles and rclpy's;
`subscription.py` raw subscriptions; `services.py` rclpy's clients and rmw's view of services;
`actions.py` goals through rclpy's ActionClient. Message bytes stay rosbags' CDR both ways: the
subscriptions take serialized messages (`raw=True`) and the publishers publish bytes.
"""
