"""ROS 2 services over DDS as rmw_cyclonedds_cpp carries them (Cyclone peers only).

A service `/add` is two DDS topics: requests on `rq/addRequest` (type `pkg::srv::dds_::Add_Request_`) and
replies on `rr/addReply` (`pkg::srv::dds_::Add_Response_`). rmw_cyclonedds_cpp serializes a
`cdds_request_header_t {uint64 guid; int64 seq;}` into the CDR stream in front of the message fields
(serdata.cpp, `is_request_header`), in requests and in replies alike: the client picks the guid (its
writer's instance handle), the server copies the header into its reply, and every client filters the reply
topic for its own guid. The header is 16 bytes, so the message fields keep their CDR alignment. Fast DDS
uses a different header, so its services do not interoperate with Cyclone's (a ROS 2 limit, not ours).
The DDS types rostool registers for service topics carry the header as two leading members (see
`TypeSupport._with_request_header` for why, and which peers that excludes).

rosbags' type stores hold messages only; the service types rostool itself needs are defined here from their
.srv text (rcl_interfaces parameter services, example_interfaces/AddTwoInts); others come from .srv files
in the interface sources (see definitions.py).
"""

from __future__ import annotations

import random
import struct
import threading
import time
from collections.abc import Callable
from typing import Any

from rostool.errors import RostoolError
from rostool.graph.ros2 import dds
from rostool.graph.ros2.definitions import service_types
from rostool.graph.ros2.names import reply_topic, request_topic
from rostool.graph.ros2.types import TypeSupport

SERVICE_QOS = dds.PROFILES["services_default"]
REPLY_MATCH_WAIT = 2.0  # how long a server waits for its reply writer to match a new client's reader
_ANY_SAMPLE = 0x7F

SRV_DEFINITIONS: dict[str, str] = {
    "rcl_interfaces/srv/ListParameters": "uint64 DEPTH_RECURSIVE=0\nstring[] prefixes\nuint64 depth\n"
    "---\nListParametersResult result\n",
    "rcl_interfaces/srv/GetParameters": "string[] names\n---\nParameterValue[] values\n",
    "rcl_interfaces/srv/SetParameters": "Parameter[] parameters\n---\nSetParametersResult[] results\n",
    "rcl_interfaces/srv/DescribeParameters": "string[] names\n---\nParameterDescriptor[] descriptors\n",
    "rcl_interfaces/srv/GetParameterTypes": "string[] names\n---\nuint8[] types\n",
    "action_msgs/srv/CancelGoal": "GoalInfo goal_info\n---\nint8 ERROR_NONE=0\nint8 ERROR_REJECTED=1\n"
    "int8 ERROR_UNKNOWN_GOAL_ID=2\nint8 ERROR_GOAL_TERMINATED=3\n"
    "int8 return_code\nGoalInfo[] goals_canceling\n",
    "example_interfaces/srv/AddTwoInts": "int64 a\nint64 b\n---\nint64 sum\n",
    "example_interfaces/srv/SetBool": "bool data\n---\nbool success\nstring message\n",
    "example_interfaces/srv/Trigger": "---\nbool success\nstring message\n",
    "std_srvs/srv/Empty": "---\n",
    "std_srvs/srv/SetBool": "bool data\n---\nbool success\nstring message\n",
    "std_srvs/srv/Trigger": "---\nbool success\nstring message\n",
    # REP 2016, served by every node from Iron on (see type_description.py)
    "type_description_interfaces/srv/GetTypeDescription": "string type_name\nstring type_hash\n"
    "bool include_type_sources true\n---\nbool successful\nstring failure_reason\n"
    "TypeDescription type_description\nTypeSource[] type_sources\nKeyValue[] extra_information\n",
}


def register_service(types: TypeSupport, srv_type: str, text: str | None = None) -> tuple[str, str]:
    """Make `pkg/srv/Name_Request` and `_Response` known to the session's store; returns both names.

    Looked up in order: the store, `text`, rostool's built-in definitions, then .srv source files."""
    parts = srv_type.strip().strip("/").split("/")
    if len(parts) == 2:
        pkg, name = parts
        kind = "srv"
    elif len(parts) == 3 and parts[1] in ("srv", "action"):  # actions' services are `pkg/action/X_SendGoal`
        pkg, kind, name = parts
    else:
        raise RostoolError(f"bad service type {srv_type!r}: use pkg/srv/Name (or pkg/Name)")
    full = f"{pkg}/{kind}/{name}"
    request, response = f"{full}_Request", f"{full}_Response"
    if types.in_store(request) and types.in_store(response):
        return request, response
    text = text if text is not None else SRV_DEFINITIONS.get(full)
    if text is None:
        if types.knows(request) and types.knows(response):
            return request, response
        raise types.unknown("service", full, sorted(SRV_DEFINITIONS))
    types.register(service_types(full, text, f"the definition of {full}"))
    return request, response


def _split(payload: bytes) -> tuple[int, int, bytes]:
    """(guid, seq, plain CDR of the message) of a request or reply sample."""
    if len(payload) < 20:
        raise ValueError("too short for a request header")
    order = "<" if payload[1] == 1 else ">"
    guid, seq = struct.unpack_from(order + "Qq", payload, 4)
    return guid, seq, payload[:4] + payload[20:]


def _join(guid: int, seq: int, cdr: bytes) -> bytes:
    order = "<" if cdr[1] == 1 else ">"
    return cdr[:4] + struct.pack(order + "Qq", guid, seq) + cdr[4:]


class ServiceClient:
    """Calls one service; `call` waits until a server has matched both topics."""

    def __init__(self, session: Any, service: str, srv_type: str) -> None:
        self._session = session
        self._types: TypeSupport = session.types
        self.service = service
        self.request_type, self.response_type = register_service(self._types, srv_type)
        self._writer = session.writer(request_topic(service), self.request_type, SERVICE_QOS, True)
        self._reader = session.reader(reply_topic(service), self.response_type, SERVICE_QOS, True)
        self._guid = random.getrandbits(63) or 1
        self._seq = 0
        self._lock = threading.Lock()

    def wait_for_server(self, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while True:
            writer_ok = self._writer.get_publication_matched_status().current_count > 0
            reader_ok = self._reader.get_subscription_matched_status().current_count > 0
            if writer_ok and reader_ok:
                return True
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)

    def call(self, request: object, timeout: float = 5.0) -> Any:
        from cyclonedds._clayer import ddspy_take, ddspy_write  # type: ignore[import-not-found]

        if not self.wait_for_server(timeout):
            raise RostoolError(
                f"service {self.service} is not available (no server matched within {timeout:g} s)"
            )
        with self._lock:
            self._seq += 1
            seq = self._seq
            payload = _join(self._guid, seq, self._types.serialize(request, self.request_type))
            if ddspy_write(self._writer._ref, payload) < 0:
                raise RostoolError(f"DDS write of a request to {self.service} failed")
            deadline = time.monotonic() + timeout
            while time.monotonic() < deadline:
                samples = ddspy_take(self._reader._ref, _ANY_SAMPLE, 64)
                for data, info in [] if isinstance(samples, int) else samples:
                    if not info.valid_data:
                        continue
                    guid, got_seq, cdr = _split(data)
                    if guid == self._guid and got_seq == seq:
                        return self._types.deserialize(cdr, self.response_type)
                time.sleep(0.005)
        raise RostoolError(f"service {self.service} did not reply within {timeout:g} s")

    def close(self) -> None:
        """Delete this client's request writer and reply reader (a one-off call leaves nothing behind)."""
        self._session.drop(self._writer)
        self._session.drop(self._reader)


class ServiceServer:
    """Serves one service from a thread: `handler(request) -> response message`."""

    def __init__(self, session: Any, service: str, srv_type: str, handler: Callable[[Any], object]) -> None:
        from cyclonedds.core import ReadCondition, WaitSet

        self._types: TypeSupport = session.types
        self.service = service
        self.request_type, self.response_type = register_service(self._types, srv_type)
        self._reader = session.reader(request_topic(service), self.request_type, SERVICE_QOS, True)
        self._writer = session.writer(reply_topic(service), self.response_type, SERVICE_QOS, True)
        self._handler = handler
        self._closed = threading.Event()
        self._waitset = WaitSet(session.participant.dp)
        self._waitset.attach(ReadCondition(self._reader, _ANY_SAMPLE))
        self._thread = threading.Thread(target=self._serve, name=f"ros2 service {service}", daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        from cyclonedds._clayer import ddspy_take, ddspy_write  # type: ignore[import-not-found]
        from cyclonedds.util import duration

        while not self._closed.is_set():
            self._waitset.wait(duration(milliseconds=250))
            samples = ddspy_take(self._reader._ref, _ANY_SAMPLE, 64)
            for data, info in [] if isinstance(samples, int) else samples:
                if not info.valid_data:
                    continue
                guid, seq, cdr = _split(data)
                response = self._handler(self._types.deserialize(cdr, self.request_type))
                reply = _join(guid, seq, self._types.serialize(response, self.response_type))
                self._wait_for_reply_readers()
                ddspy_write(self._writer._ref, reply)

    def _wait_for_reply_readers(self, timeout: float = REPLY_MATCH_WAIT) -> None:
        """Discovery matches each direction on its own: a client may see us (and send a request) before our
        reply writer has matched its reply reader, and a volatile reply written then is lost. Every client
        has one request writer and one reply reader, so wait until we match as many readers as writers."""
        deadline = time.monotonic() + timeout
        while (
            self._writer.get_publication_matched_status().current_count
            < self._reader.get_subscription_matched_status().current_count
            and time.monotonic() < deadline
        ):
            time.sleep(0.005)

    def close(self) -> None:
        self._closed.set()
        self._waitset.set_trigger(True)
        self._thread.join(2.0)
