"""ROS 2 through the user's own client library and middleware: a Graph on rclpy.

`select.py` decides between this backend and the DDS one without importing rclpy (and says why);
`facts.py` what `rostool doctor` reports; `context.py` the rclpy context, node and executor thread;
`graph.py` the Graph the verbs use; `types.py` message classes rclpy imports and their rosbags twins;
`qos.py` QoS between rostool's profiles and rclpy's; `subscription.py` raw subscriptions; `services.py`,
`params.py`, `actions.py` (their protocol methods in `verbs.py`) and `recording.py` (bag play and record) the
rest of the Graph protocol, with the DDS backend's lines and output. Message bytes stay rosbags' CDR both
ways: the subscriptions take serialized messages (`raw=True`) and the publishers publish bytes.
"""
