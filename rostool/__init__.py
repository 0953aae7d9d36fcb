"""rostool: one command-line toolbox for ROS 1 and ROS 2 graphs and bags."""

__version__ = "0.1.0"
