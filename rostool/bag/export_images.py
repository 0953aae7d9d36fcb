"""sensor_msgs Image and CompressedImage messages as PNG files (Pillow) or one MP4 per topic (PyAV).

PNG files are named by the receive time in nanoseconds: DIR/TOPIC/<t>.png. An MP4 keeps the frames'
real timing (presentation times from the receive times, in milliseconds).
"""

from __future__ import annotations

import io
from fractions import Fraction
from pathlib import Path
from typing import Any

from rostool.bag.failures import warn

# encoding -> (channels, numpy dtype, Pillow mode after conversion, reorder to RGB(A))
_ENCODINGS: dict[str, tuple[int, str, str, bool]] = {
    "rgb8": (3, "u1", "RGB", False),
    "bgr8": (3, "u1", "RGB", True),
    "8uc3": (3, "u1", "RGB", True),  # OpenCV's default order is BGR
    "rgba8": (4, "u1", "RGBA", False),
    "bgra8": (4, "u1", "RGBA", True),
    "8uc4": (4, "u1", "RGBA", True),
    "mono8": (1, "u1", "L", False),
    "8uc1": (1, "u1", "L", False),
    "mono16": (1, "u2", "I;16", False),
    "16uc1": (1, "u2", "I;16", False),
}
SUPPORTED = ", ".join(sorted(name for name in _ENCODINGS if not name[0].isdigit()))


def image_array(msg: Any) -> Any:
    """A raw sensor_msgs/Image as a numpy array (H, W) or (H, W, C) in RGB(A) order; ValueError when its
    encoding is not supported or its data is short."""
    import numpy as np

    encoding = str(msg.encoding).lower()
    if encoding not in _ENCODINGS:
        raise ValueError(f"encoding {msg.encoding!r} is not supported (supported: {SUPPORTED})")
    channels, kind, _mode, reorder = _ENCODINGS[encoding]
    height, width, step = int(msg.height), int(msg.width), int(msg.step)
    dtype = np.dtype(kind).newbyteorder(">" if msg.is_bigendian else "<")
    row = width * channels * dtype.itemsize
    data = np.frombuffer(bytes(msg.data) if not hasattr(msg.data, "tobytes") else msg.data, dtype=np.uint8)
    step = step or row
    if step < row or len(data) < step * (height - 1) + row:
        raise ValueError(
            f"{width}x{height} {msg.encoding} needs {step * height} bytes, the message has {len(data)}"
        )
    rows = np.lib.stride_tricks.as_strided(data, shape=(height, row), strides=(step, 1))
    pixels = np.ascontiguousarray(rows).view(dtype).reshape(height, width, channels)
    if dtype.itemsize > 1:
        pixels = pixels.astype("<u2")
    if reorder:
        pixels = pixels[:, :, [2, 1, 0, 3][:channels]]
    return pixels[:, :, 0] if channels == 1 else pixels


def to_pillow(msg: Any) -> Any:
    from PIL import Image

    if getattr(msg, "__msgtype__", "").endswith("CompressedImage"):
        image = Image.open(io.BytesIO(bytes(msg.data)))
        image.load()
        return image
    pixels = image_array(msg)
    mode = _ENCODINGS[str(msg.encoding).lower()][2]
    return Image.fromarray(pixels, mode=mode) if mode != "I;16" else Image.fromarray(pixels)


class ImageSink:
    """One topic's images: PNG files in DIR/NAME/, or DIR/NAME.mp4 with `video`."""

    def __init__(self, base: Path, name: str, topic: str, video: bool = False) -> None:
        self.topic = topic
        self.video = video
        self.folder = base / name
        self.mp4 = base / f"{name}.mp4"
        self.written: list[Path] = []
        self._warned = False
        self._encoder: _Mp4 | None = None

    def add(self, msg: Any, timestamp: int) -> int:
        try:
            image = to_pillow(msg)
        except Exception as err:  # one bad frame (or an unsupported encoding) does not end the export
            if not self._warned:
                self._warned = True
                warn(f"{self.topic}: images left out: {err}")
            return 0
        if self.video:
            if self._encoder is None:
                self._encoder = _Mp4(self.mp4, image.size, timestamp)
            self._encoder.add(image, timestamp)
            return 1
        self.folder.mkdir(parents=True, exist_ok=True)
        path = self.folder / f"{timestamp}.png"
        image.save(path, format="PNG", compress_level=1)
        self.written.append(path)
        return 1

    def close(self) -> list[Path]:
        if self._encoder is not None:
            self._encoder.close()
            return [self.mp4]
        return [self.folder] if self.written else []

    def discard(self) -> None:
        if self._encoder is not None:
            self._encoder.close()
            self.mp4.unlink(missing_ok=True)


class _Mp4:
    """H.264 (yuv420p needs even sizes: odd ones are scaled up a pixel), millisecond presentation times."""

    def __init__(self, path: Path, size: tuple[int, int], start_ns: int) -> None:
        import av

        path.parent.mkdir(parents=True, exist_ok=True)
        self.container = av.open(str(path), mode="w")
        codec = "libx264" if "libx264" in av.codecs_available else "mpeg4"  # mpeg4 is FFmpeg's own
        self.stream = self.container.add_stream(codec, rate=30)
        self.stream.width, self.stream.height = size[0] + size[0] % 2, size[1] + size[1] % 2
        self.stream.pix_fmt = "yuv420p"
        self.stream.time_base = Fraction(1, 1000)
        self.start_ns = start_ns
        self.last_pts = -1
        self._av = av

    def add(self, image: Any, timestamp: int) -> None:
        if image.mode != "RGB":
            image = (
                image.convert("RGB")
                if image.mode != "I;16"
                else image.point(lambda v: v / 256).convert("RGB")
            )
        if image.size != (self.stream.width, self.stream.height):
            image = image.resize((self.stream.width, self.stream.height))
        frame = self._av.VideoFrame.from_image(image)
        pts = max((timestamp - self.start_ns) // 1_000_000, self.last_pts + 1)
        frame.pts, frame.time_base = pts, Fraction(1, 1000)
        self.last_pts = pts
        for packet in self.stream.encode(frame):
            self.container.mux(packet)

    def close(self) -> None:
        for packet in self.stream.encode():
            self.container.mux(packet)
        self.container.close()
