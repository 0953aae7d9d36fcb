"""ROS 2 services over DDS, with the request/reply convention of the server's RMW.

A service `/add` is two DDS topics: requests on `rq/addRequest` (type `pkg::srv::dds_::Add_Request_`) and
replies on `rr/addReply` (`pkg::srv::dds_::Add_Response_`). The two RMWs rostool meets pair a reply with
its request differently, and the client picks the convention of the server it found, by the vendor id
that starts the server participant's GUID prefix (01.10 Eclipse Cyclone DDS, 01.0f eProsima Fast DDS):

- rmw_cyclonedds_cpp serializes a `cdds_request_header_t {uint64 guid; int64 seq;}` into the CDR stream in
  front of the message fields (serdata.cpp, `is_request_header`), in requests and in replies alike: the
  client picks the guid, the server copies the header into its reply, and every client filters the reply
  topic for its own guid. The header is 16 bytes, so the message fields keep their CDR alignment. The DDS
  types rostool registers for these topics carry the header as two leading members (see
  `TypeSupport._with_request_header` for why, and which peers that excludes).
- rmw_fastrtps_cpp puts nothing in the payload: the server takes the request's RTPS sample identity
  (writer GUID, sequence number) and sends it back as the reply's `related_sample_identity` inline QoS,
  by which rmw_fastrtps clients filter. Cyclone DDS neither sets nor shows that identity, so a rostool
  client of a Fast DDS server has one request outstanding at a time (calls through one client are
  serialized) and takes the first reply that arrives after its request as the answer. The server's reply
  writer sends every reply to every matched reader, so another client calling the same server at that very
  moment could have its reply taken instead: a limit of talking Fast DDS's convention through Cyclone.

Cyclone accepts data from a non-Cyclone reliable writer only after the writer's first HEARTBEAT, and
treats everything that heartbeat announces as history a volatile reader must not get. Fast DDS sends that
first heartbeat right before the reply when nothing came earlier, and the reply was lost (found on Jazzy
and Kilted). So the client creates its reply reader only once Cyclone knows the server's reply writer:
the heartbeat Fast DDS sends when it matches the new reader is then accepted, and replies come after it.

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
from rostool.graph.ros2.types import TypeSupport
from rostool.graph.ros2_base.calls import ReplyWait, ServiceTimeout
from rostool.graph.ros2_base.names import reply_topic, request_topic
from rostool.graph.ros2_base.qos import PROFILES
from rostool.interfaces.ros2_srv import register_service

SERVICE_QOS = PROFILES["services_default"]
REPLY_MATCH_WAIT = 2.0  # how long a server waits for its reply writer to match a new client's reader
_ANY_SAMPLE = 0x7F


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


ECLIPSE_VENDOR = b"\x01\x10"  # GUID prefix of Cyclone DDS participants (rmw_cyclonedds_cpp, rostool)
_GONE_CHECK = 1.0  # a call without a deadline checks this often that its server is still matched


def remote_writer_known(session: Any, dds_topic: str) -> bool:
    """Has discovery shown a writer of `dds_topic` in another participant (Cyclone then has its proxy)?"""
    cache = session.cache
    cache.poll()
    return any(e.dds_topic == dds_topic and e.is_writer for e in cache.remote_endpoints())


class ServiceClient(ReplyWait):
    """Calls one service. `wait_for_server` (which `call` does first) finds a server in discovery, picks
    its convention (see the module's docstring) and creates the DDS reader and writer, then waits until
    both have matched it."""

    def __init__(self, session: Any, service: str, srv_type: str) -> None:
        super().__init__()
        self._session = session
        self._types: TypeSupport = session.types
        self.service = service
        self.request_type, self.response_type = register_service(self._types, srv_type)
        self._writer: Any = None
        self._reader: Any = None
        self.header: bool | None = None  # True: rmw_cyclonedds_cpp's in-payload header; None: no server yet
        self._guid = random.getrandbits(63) or 1
        self._seq = 0

    def _server(self) -> bytes | None:
        """The participant GUID of a discovered server: one with a reader of our request topic and a writer
        of our reply topic (Cyclone then knows that writer, see the module's docstring)."""
        cache = self._session.cache
        cache.poll()
        readers: set[bytes] = set()
        writers: set[bytes] = set()
        wanted_request, wanted_reply = request_topic(self.service), reply_topic(self.service)
        for endpoint in cache.remote_endpoints():
            if endpoint.dds_topic == wanted_request and not endpoint.is_writer:
                readers.add(endpoint.participant)
            elif endpoint.dds_topic == wanted_reply and endpoint.is_writer:
                writers.add(endpoint.participant)
        both = sorted(readers & writers)
        return both[0] if both else None

    def _open(self, server: bytes) -> None:
        header = server[:2] == ECLIPSE_VENDOR
        replies, requests = reply_topic(self.service), request_topic(self.service)
        for dds_name, store_name in ((replies, self.response_type), (requests, self.request_type)):
            topic = self._session.topic(dds_name, store_name, header)
            if getattr(topic, "data_type", None) is not self._types.idl_class(store_name, header):
                other = "rmw_cyclonedds_cpp's" if not header else "rmw_fastrtps_cpp's"
                raise RostoolError(
                    f"this process already talks to {self.service} with {other} request/reply convention "
                    "and cannot use the other one too: call the other server from a second rostool"
                )
        # the reader first: see the module's docstring
        self._reader = self._session.reader(replies, self.response_type, SERVICE_QOS, header)
        self._writer = self._session.writer(requests, self.request_type, SERVICE_QOS, header)
        self.header = header

    def _matched(self) -> bool:
        return bool(
            self._writer.get_publication_matched_status().current_count > 0
            and self._reader.get_subscription_matched_status().current_count > 0
        )

    def wait_for_server(self, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while True:
            if self._writer is None:
                server = self._server()
                if server is not None:
                    self._open(server)
            if self._writer is not None and self._matched():
                return True
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)

    def _exchange(self, request: object, deadline: float, timeout: float) -> Any:
        from cyclonedds._clayer import ddspy_take, ddspy_write  # type: ignore[import-not-found]

        payload = self._types.serialize(request, self.request_type)
        self._seq += 1
        seq = self._seq
        if self.header:
            payload = _join(self._guid, seq, payload)
        else:
            self._take_all()  # a late reply to an earlier call must not pass for this one's
        if ddspy_write(self._writer._ref, payload) < 0:
            raise RostoolError(f"DDS write of a request to {self.service} failed")
        next_check = time.monotonic() + _GONE_CHECK
        while time.monotonic() < deadline:
            samples = ddspy_take(self._reader._ref, _ANY_SAMPLE, 64)
            for data, info in [] if isinstance(samples, int) else samples:
                if not info.valid_data:
                    continue
                if not self.header:
                    return self._types.deserialize(data, self.response_type)
                guid, got_seq, cdr = _split(data)
                if guid == self._guid and got_seq == seq:
                    return self._types.deserialize(cdr, self.response_type)
            if time.monotonic() >= next_check:
                next_check = time.monotonic() + _GONE_CHECK
                if not self._matched():
                    raise self._gone()
            time.sleep(0.005)
        raise ServiceTimeout(self._timeout_text(timeout))

    def _timeout_text(self, timeout: float) -> str:
        text = f"service {self.service} did not reply within {timeout:g} s"
        if self.header is False:
            text += (
                " (a Fast DDS server; if another client called it at the same moment, call again: replies "
                "cannot be told apart through Cyclone DDS)"
            )
        return text + "; give a longer --timeout if the service is slow"

    def _take_all(self) -> None:
        from cyclonedds._clayer import ddspy_take  # type: ignore[import-not-found]

        while True:
            samples = ddspy_take(self._reader._ref, _ANY_SAMPLE, 64)
            if isinstance(samples, int) or not samples:
                return

    def close(self) -> None:
        """Delete this client's request writer and reply reader (a one-off call leaves nothing behind)."""
        for endpoint in (self._writer, self._reader):
            if endpoint is not None:
                self._session.drop(endpoint)
        self._writer = self._reader = None


class ServiceServer:
    """Serves one service from a thread: `handler(request) -> response message`."""

    def __init__(self, session: Any, service: str, srv_type: str, handler: Callable[[Any], object]) -> None:
        from cyclonedds.core import ReadCondition

        from rostool.graph.ros2.dds import wakeable_waitset

        self._types: TypeSupport = session.types
        self.service = service
        self.request_type, self.response_type = register_service(self._types, srv_type)
        self._reader = session.reader(request_topic(service), self.request_type, SERVICE_QOS, True)
        self._writer = session.writer(reply_topic(service), self.response_type, SERVICE_QOS, True)
        self._handler = handler
        self._closed = threading.Event()
        self._waitset = wakeable_waitset(session.participant.dp)
        self._waitset.attach(ReadCondition(self._reader, _ANY_SAMPLE))
        self._thread = threading.Thread(target=self._serve, name=f"ros2 service {service}", daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        from cyclonedds._clayer import ddspy_take, ddspy_write  # type: ignore[import-not-found]
        from cyclonedds.core import DDSException
        from cyclonedds.util import duration

        while not self._closed.is_set():
            try:
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
            except DDSException:
                # its entities were deleted under it: the participant closed before `close` was called (a
                # Ctrl+C between the server's start and its registration) or before its join ended
                return

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
        if self._closed.is_set():  # closed by its owner and again by the graph's close
            return
        self._closed.set()
        self._waitset.wakeup.set(True)
        self._thread.join(2.0)
