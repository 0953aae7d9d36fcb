"""`rostool bag export`: Parquet and CSV tables equal `bag echo --json`, message by message; images decode."""

from __future__ import annotations

import csv
import json
import math
from collections import defaultdict
from pathlib import Path
from typing import Any

import pytest

from tests.support import rostool
from tests.test_bag_support import ALL_BAGS, env, shared, true_counts

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")


def topic_file(topic: str) -> str:
    return topic.strip("/").replace("/", ".")


def echo_by_topic(path: Path) -> dict[str, list[dict[str, Any]]]:
    """{topic: [{"t": seconds, "msg": ...}]} from `rostool bag echo --json` (the reference)."""
    from rostool.bag.reader import BagReader

    with BagReader([path]) as reader:
        topics = sorted({conn.topic for conn in reader.connections})
    result = rostool(["bag", "echo", str(path), "--json"], env(), timeout=120)
    assert result.returncode == 0, result.stderr
    rows: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for line in result.stdout.splitlines():
        value = json.loads(line)
        if len(topics) == 1:
            value = {"topic": topics[0], "t": None, "msg": value}
        rows[value["topic"]].append(value)
    return rows


def unflatten(row: dict[str, Any]) -> dict[str, Any]:
    """A table row (dotted column names) back to the nested message, byte arrays as lists of ints."""
    out: dict[str, Any] = {}
    for name, value in row.items():
        if name in ("t", "stamp"):
            continue
        *parents, leaf = name.split(".")
        node = out
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = plain(value)
    return out


def plain(value: Any) -> Any:
    if isinstance(value, bytes):
        return list(value)
    if isinstance(value, dict):  # an empty message's struct has one placeholder member
        return {
            key: plain(item) for key, item in value.items() if key != "structure_needs_at_least_one_member"
        }
    if isinstance(value, list):
        return [plain(item) for item in value]
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    return value


def flatten(msg: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name, value in msg.items():
        if isinstance(value, dict):
            out.update(flatten(value, f"{prefix}{name}."))
        else:
            out[f"{prefix}{name}"] = value
    return out


def csv_equals(cell: str, expected: Any) -> bool:
    if isinstance(expected, (list, dict)):
        return bool(json.loads(cell) == expected)
    if isinstance(expected, bool):
        return cell == ("true" if expected else "false")
    if isinstance(expected, str):
        return cell == expected
    return float(cell) == expected


def stamp_ns(msg: dict[str, Any]) -> int:
    stamp = msg["header"]["stamp"]
    sec, nanosec = (stamp["secs"], stamp["nsecs"]) if "secs" in stamp else (stamp["sec"], stamp["nanosec"])
    return int(sec) * 1_000_000_000 + int(nanosec)


@pytest.mark.parametrize("name", ALL_BAGS)
def test_tables_equal_echo_json(name: str, tmp_path: Path) -> None:
    path = shared(name)
    expected = echo_by_topic(path)
    counts = true_counts(path)
    for fmt in ("parquet", "csv"):
        out = tmp_path / fmt
        result = rostool(["bag", "export", str(path), "--format", fmt, "-o", str(out)], env(), timeout=120)
        assert result.returncode == 0, result.stderr
        assert result.stderr.startswith(f"exported {sum(counts.values())} messages")
        for topic, count in counts.items():
            table = out / f"{topic_file(topic)}.{fmt}"
            rows = read_rows(table, fmt)
            assert len(rows) == count == len(expected[topic])
            for row, echoed in zip(rows, expected[topic], strict=True):
                if echoed["t"] is not None:
                    assert abs(int(row["t"]) / 1e9 - echoed["t"]) < 1e-6
                msg = echoed["msg"]
                if "header" in msg and isinstance(msg["header"], dict) and "stamp" in msg["header"]:
                    assert int(row["stamp"]) == stamp_ns(msg)
                if fmt == "parquet":
                    assert unflatten(row) == msg
                else:
                    flat = flatten(msg)
                    assert [key for key in row if key not in ("t", "stamp")] == list(flat)
                    for key, value in flat.items():
                        assert csv_equals(row[key], value), (topic, key, row[key], value)


def read_rows(path: Path, fmt: str) -> list[dict[str, Any]]:
    if fmt == "parquet":
        return list(pq.read_table(path).to_pylist())
    with path.open(newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def test_parquet_columns_are_typed(tmp_path: Path) -> None:
    out = tmp_path / "out"
    path = shared("ros2/cdr_test_mcap")
    assert rostool(["bag", "export", str(path), "-o", str(out)], env()).returncode == 0
    basic = pq.read_schema(out / "test_topic.parquet")
    assert basic.field("t").type == pa.int64()
    assert basic.field("bool_value").type == pa.bool_()
    assert basic.field("int32_value").type == pa.int32()
    assert basic.field("uint64_value").type == pa.uint64()
    assert basic.field("float32_value").type == pa.float32()
    assert basic.field("float64_value").type == pa.float64()
    arrays = pq.read_schema(out / "array_topic.parquet")
    assert arrays.field("string_values").type == pa.list_(pa.string())
    assert arrays.field("float64_values").type == pa.list_(pa.float64())
    assert pa.types.is_struct(arrays.field("basic_types_values").type.value_type)
    ros1 = tmp_path / "ros1"
    assert rostool(["bag", "export", str(shared("ros1/example.bag")), "-o", str(ros1)], env()).returncode == 0
    pose = pq.read_schema(ros1 / "turtle1.pose.parquet")
    assert [pose.field(n).type for n in ("x", "theta")] == [pa.float32(), pa.float32()]
    log = pq.read_schema(ros1 / "rosout.parquet")
    assert log.field("stamp").type == pa.int64()
    assert log.field("header.stamp.secs").type == pa.int32()
    assert log.field("msg").type == pa.string()


@pytest.mark.parametrize(
    ("name", "line"),
    [
        ("ros1/empty-file.bag", "empty file (0 bytes), not a bag"),
        ("ros1/asci-file.txt", "not a bag"),
    ],
)
def test_broken_bag_is_one_line(name: str, line: str, tmp_path: Path) -> None:
    result = rostool(["bag", "export", str(shared(name)), "-o", str(tmp_path / "out")], env())
    assert result.returncode == 1
    assert result.stderr.count("\n") == 1 and line in result.stderr and "Traceback" not in result.stderr
    assert not list((tmp_path / "out").rglob("*.parquet"))


def test_topics_option_and_unknown_topic(tmp_path: Path) -> None:
    path = shared("ros1/example.bag")
    out = tmp_path / "out"
    result = rostool(["bag", "export", str(path), "--topics", "/turtle1/pose,/rosout", "-o", str(out)], env())
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in out.iterdir()) == ["rosout.parquet", "turtle1.pose.parquet"]
    bad = rostool(["bag", "export", str(path), "--topics", "/nope", "-o", str(out)], env())
    assert bad.returncode == 1 and bad.stderr.count("\n") == 1 and "/nope is not in the bag" in bad.stderr


def write_image_bag(path: Path) -> dict[str, Any]:
    """A rosbag2 bag (rosbags' writer) with raw Images in five encodings and PNG/JPEG CompressedImages."""
    import io

    import numpy as np
    from PIL import Image
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    types = store.types
    pixels: dict[str, Any] = {}
    with Writer(path, version=9) as writer:
        raw = writer.add_connection("/camera/raw", "sensor_msgs/msg/Image", typestore=store)
        packed = writer.add_connection(
            "/camera/compressed", "sensor_msgs/msg/CompressedImage", typestore=store
        )
        encodings = [("rgb8", 3, np.uint8), ("bgr8", 3, np.uint8), ("mono8", 1, np.uint8),
                     ("mono16", 1, np.uint16), ("rgba8", 4, np.uint8)]  # fmt: skip
        for i, (encoding, channels, dtype) in enumerate(encodings):
            height, width = 6, 10
            values = ((np.arange(height * width * channels) * 7 + i) % 250).astype(dtype)
            if dtype == np.uint16:
                values = values * 250  # above 255: 16-bit depth survives
            image = values.reshape(height, width, channels)
            pixels[encoding] = image
            stamp = 1_700_000_000_000_000_000 + i * 100_000_000
            time = types["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9)
            header = types["std_msgs/msg/Header"](stamp=time, frame_id="camera")
            data = np.frombuffer(image.tobytes(), dtype=np.uint8)
            msg = types["sensor_msgs/msg/Image"](
                header, height, width, encoding, 0, width * channels * image.itemsize, data
            )
            writer.write(raw, stamp, store.serialize_cdr(msg, "sensor_msgs/msg/Image"))
            buffer = io.BytesIO()
            Image.new("RGB", (8, 4), (255, 0, 0)).save(buffer, format="JPEG" if i % 2 else "PNG")
            compressed = types["sensor_msgs/msg/CompressedImage"](
                header, "jpeg" if i % 2 else "png", np.frombuffer(buffer.getvalue(), dtype=np.uint8)
            )
            writer.write(
                packed, stamp + 1, store.serialize_cdr(compressed, "sensor_msgs/msg/CompressedImage")
            )
    return pixels


def test_images_as_png(tmp_path: Path) -> None:
    import numpy as np
    from PIL import Image

    bag = tmp_path / "camera"
    pixels = write_image_bag(bag)
    out = tmp_path / "frames"
    result = rostool(["bag", "export", str(bag), "--images", str(out)], env())
    assert result.returncode == 0, result.stderr
    assert "(10 images)" in result.stderr
    files = sorted((out / "camera.raw").iterdir())
    assert [f.name for f in files] == [f"{1_700_000_000_000_000_000 + i * 100_000_000}.png" for i in range(5)]
    decoded = [Image.open(f) for f in files]
    assert [(im.size, im.mode) for im in decoded] == [
        ((10, 6), m) for m in ("RGB", "RGB", "L", "I;16", "RGBA")
    ]
    arrays = [np.asarray(im) for im in decoded]
    assert (arrays[0] == pixels["rgb8"]).all()
    assert (arrays[1] == pixels["bgr8"][:, :, ::-1]).all()  # stored BGR, written RGB
    assert (arrays[2] == pixels["mono8"][:, :, 0]).all()
    assert (arrays[3] == pixels["mono16"][:, :, 0]).all() and arrays[3].max() > 255
    assert (arrays[4] == pixels["rgba8"]).all()
    compressed = sorted((out / "camera.compressed").iterdir())
    assert len(compressed) == 5
    for file in compressed:
        image = Image.open(file)
        assert image.format == "PNG" and image.size == (8, 4)
        assert image.convert("RGB").getpixel((0, 0))[0] > 240  # red, also after JPEG


def test_images_as_video(tmp_path: Path) -> None:
    av = pytest.importorskip("av")
    bag = tmp_path / "camera"
    write_image_bag(bag)
    out = tmp_path / "videos"
    result = rostool(
        ["bag", "export", str(bag), "--images", str(out), "--video", "--topics", "/camera/raw"], env()
    )
    assert result.returncode == 0, result.stderr
    with av.open(str(out / "camera.raw.mp4")) as container:
        frames = list(container.decode(video=0))
        times = [float(frame.time) for frame in frames]
    assert len(frames) == 5 and (frames[0].width, frames[0].height) == (10, 6)
    assert times == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4], abs=0.002)  # the bag's own timing


def test_parquet_image_table_keeps_the_bytes(tmp_path: Path) -> None:
    bag = tmp_path / "camera"
    pixels = write_image_bag(bag)
    out = tmp_path / "tables"
    assert rostool(["bag", "export", str(bag), "-o", str(out)], env()).returncode == 0
    table = pq.read_table(out / "camera.raw.parquet")
    assert table.schema.field("data").type == pa.binary()
    assert table.column("encoding").to_pylist() == ["rgb8", "bgr8", "mono8", "mono16", "rgba8"]
    assert table.column("data")[0].as_py() == pixels["rgb8"].tobytes()


def test_a_missing_extra_is_one_line(tmp_path: Path) -> None:
    """Without pyarrow (here: a pyarrow that fails to import, first on the path) Parquet names the extra;
    CSV needs no extra."""
    fake = tmp_path / "site" / "pyarrow"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise ImportError('no pyarrow here')\n")
    without = {**env(), "PYTHONPATH": str(tmp_path / "site")}
    path = str(shared("ros2/talker_mcap"))
    result = rostool(["bag", "export", path, "-o", str(tmp_path / "out")], without)
    assert result.returncode == 1
    assert result.stderr == (
        "rostool: --format parquet needs the pyarrow module: pip install 'rostool[export]'\n"
    )
    csv_out = rostool(["bag", "export", path, "--format", "csv", "-o", str(tmp_path / "csv")], without)
    assert csv_out.returncode == 0, csv_out.stderr
    assert (tmp_path / "csv" / "topic.csv").read_text().splitlines()[1].endswith(',"Hello, world! 0"')
