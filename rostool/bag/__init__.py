"""Bags: one reader/writer abstraction over ROS 1 `.bag`, rosbag2 directories, `.mcap` and `.db3` files.

Built on `rosbags` (reading, writing, type stores, ROS 1 <-> CDR conversion) and `mcap` (summary reading).
Modules: `open` (input detection), `typestores`, `reader`, `info`, `convert` (also filter), `reindex`.
"""
