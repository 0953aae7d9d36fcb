"""Bags: one reader/writer abstraction over ROS 1 `.bag`, rosbag2 directories, `.mcap` and `.db3` files.

Built on `rosbags` (reading, writing, type stores, ROS 1 <-> CDR conversion) and `mcap` (summary reading).
Floors, each importing only those below it:
- `model` (the data: BagInput, BagInfo, ReindexResult, a format table row), `failures` (one-line errors),
  `rosbag2_metadata` (metadata.yaml), `ros1_format`, `bounded`, `replace`, `schedule`, `crossver`;
- format modules, each knowing its own format only: `ros1_info`, `mcap_info`, `db3_info`, `ros1_reindex`,
  `mcap_reindex`, `rosbag2_reindex`, `ros1_writer`, `record_sinks`, `mcap_batches`, `columnar`;
- `formats`: the format table (facts, rosbags reader, info and reindex of each format);
- what works on any bag through it: `open` (input detection), `reader`, `info`, `reindex`, `convert` (also
  filter), `record`, `play`/`play_ros2`, `export`, `echo`, `many` (several bags at once), `ray_engine`, and
  the verbs' engines over them (`copy_many`, `export_many`, `message_filter`, `play_topics`, `qos_overrides`,
  `record_select`).
"""
