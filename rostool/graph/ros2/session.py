"""One DDS participant with rmw_dds_common's graph machinery: the node it announces on
ros_discovery_info, the topics, readers and writers it creates (with the type hash in USER_DATA), and
the graph cache discovery fills."""

from __future__ import annotations

import contextlib
import threading
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.ros2 import dds
from rostool.graph.ros2.discovery import (
    DISCOVERY_TOPIC,
    DISCOVERY_TYPE,
    GraphCache,
    NodeEntry,
    encode_entities_info,
)
from rostool.graph.ros2.types import TypeSupport, gid_size
from rostool.graph.ros2_base.names import type_to_dds
from rostool.graph.ros2_base.qos import QosProfile


class Session:
    """One DDS participant with rmw_dds_common's graph machinery."""

    def __init__(self, node_name: str, types: TypeSupport, cache: GraphCache | None = None) -> None:
        from cyclonedds.core import Policy, Qos
        from cyclonedds.pub import DataWriter
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        self.types = types
        self.participant = cache.participant if cache is not None else dds.Participant()
        self.node = NodeEntry("/", node_name)
        self._lock = threading.RLock()
        self._topics: dict[str, Any] = {}
        self._keep: list[Any] = []
        info_cls = types.idl_class(DISCOVERY_TYPE)
        info_topic: Any = Topic(self.participant.dp, DISCOVERY_TOPIC, info_cls)
        user_data = types.user_data(DISCOVERY_TYPE)
        graph_qos = QosProfile("reliable", "transient_local", 1)
        writer_qos = dds.to_dds_qos(graph_qos, user_data)
        reader_qos = dds.to_dds_qos(QosProfile("reliable", "transient_local", 0), user_data)
        self._info_writer = DataWriter(self.participant.dp, info_topic, qos=writer_qos)
        self.cache = cache if cache is not None else GraphCache(self.participant)
        self.announce()

        def info_reader() -> Any:
            return DataReader(
                self.participant.dp, info_topic, qos=Qos(*reader_qos.policies, Policy.IgnoreLocal.Participant)
            )

        self.cache.prompt_with(info_reader)
        self.cache.defer_info_reader(info_reader)

    def announce(self) -> None:
        from cyclonedds._clayer import ddspy_write  # type: ignore[import-not-found]

        payload = encode_entities_info(self.participant.guid, [self.node], gid_size(self.types.distro))
        ddspy_write(self._info_writer._ref, payload)

    def topic(self, dds_name: str, store_name: str, request_header: bool = False) -> Any:
        from cyclonedds.core import DDSException
        from cyclonedds.topic import Topic

        with self._lock:
            found = self._topics.get(dds_name)
            if found is not None:
                if found[1] != store_name:
                    raise RostoolError(f"this process already uses {dds_name} with type {found[1]}")
                return found[0]
            try:
                data_type = self.types.idl_class(store_name, request_header)
                created: Any = Topic(self.participant.dp, dds_name, data_type)
            except DDSException as err:
                where = f"{dds_name} ({type_to_dds(store_name)})"
                raise RostoolError(f"cannot create DDS topic {where}: {err}") from err
            self._topics[dds_name] = (created, store_name)
            return created

    def writer(
        self, dds_name: str, store_name: str, profile: QosProfile, request_header: bool = False
    ) -> Any:
        from cyclonedds.pub import DataWriter

        return self._announced(DataWriter, self.node.writers, dds_name, store_name, profile, request_header)

    def reader(
        self, dds_name: str, store_name: str, profile: QosProfile, request_header: bool = False
    ) -> Any:
        from cyclonedds.sub import DataReader

        return self._announced(DataReader, self.node.readers, dds_name, store_name, profile, request_header)

    def _announced(
        self,
        kind: Any,
        announced: list[bytes],
        dds_name: str,
        store_name: str,
        profile: QosProfile,
        request_header: bool,
    ) -> Any:
        """A DDS reader or writer with the type hash in USER_DATA, listed on ros_discovery_info."""
        endpoint = kind(
            self.participant.dp, self.topic(dds_name, store_name, request_header),
            qos=dds.to_dds_qos(profile, self.types.user_data(store_name)),
        )  # fmt: skip
        with self._lock:
            announced.append(endpoint.guid.bytes)
            self.announce()
        return endpoint

    def used_types(self) -> set[str]:
        """The message types of this session's topics (service topics give their request/reply types)."""
        with self._lock:
            return {store_name for _topic, store_name in self._topics.values()}

    def drop(self, endpoint: Any) -> None:
        """Delete a reader or writer this session made and stop announcing it."""
        with self._lock:
            guid = endpoint.guid.bytes
            for announced in (self.node.readers, self.node.writers):
                if guid in announced:
                    announced.remove(guid)
                    self.announce()
        endpoint.__del__()  # cyclonedds deletes an entity only this way (or with its participant)

    def close(self) -> None:
        """Leave the graph at once: first say on ros_discovery_info that this participant has no node left
        (rmw's graph caches drop the node on that sample, as when a node is destroyed, where the
        participant's disposal alone may only be noticed when its lease expires), then delete it."""
        from cyclonedds._clayer import ddspy_write  # type: ignore[import-not-found]

        with self._lock:
            payload = encode_entities_info(self.participant.guid, [], gid_size(self.types.distro))
            with contextlib.suppress(Exception):
                ddspy_write(self._info_writer._ref, payload)
                self._info_writer.wait_for_acks(dds_duration_ms(200))
        self.participant.close()


def dds_duration_ms(milliseconds: int) -> int:
    from cyclonedds.util import duration

    return int(duration(milliseconds=milliseconds))
