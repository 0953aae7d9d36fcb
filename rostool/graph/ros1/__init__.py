"""Native ROS 1 client: XML-RPC master/slave APIs, TCPROS, embedded master."""
