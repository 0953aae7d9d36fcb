"""`rostool doctor hello`: ros2 doctor hello. Every emit period it publishes "hello, it's me <host>" as a
std_msgs String on a topic and sends the same text by UDP multicast (ros2's group and port); it counts what
other hosts say on both, and every print period prints ros2's summary table. The topic goes through the
live graph (ROS 2 on either backend, or ROS 1), opened directly as ros2's DirectNode: this process must hear
the others itself, not a graph daemon for it."""

from __future__ import annotations

import re
import socket
import threading
import time
from collections.abc import Callable
from typing import Any

import click

from rostool.commands._common import json_option, print_json, ros2_backend, ros_version
from rostool.errors import RostoolError
from rostool.graph.base import Received
from rostool.graph.multicast import GROUP, PORT, joined_socket, send_datagram, sending_socket

GREETING = "hello, it's me "  # ros2's text; what follows it is the sender's host name
RULE = "-" * 60


class Tally:
    """What was published and sent this print period, and what each other host was heard saying."""

    def __init__(self, host: str) -> None:
        self.host = host
        self.lock = threading.Lock()
        self.published = self.sent = 0
        self.subscribed: dict[str, int] = {}  # host -> messages heard on the topic, in the order first heard
        self.received: dict[str, int] = {}  # host -> datagrams heard by multicast
        self.error: str | None = None  # the subscription's one line, raised by the emit loop

    def heard(self, counts: dict[str, int], text: str) -> None:
        """Count `text` when another host says hello in it (ros2 counts the last word of anything)."""
        sender = text[len(GREETING) :].strip() if text.startswith(GREETING) else ""
        if sender and sender != self.host:
            with self.lock:
                counts[sender] = counts.get(sender, 0) + 1

    def on_message(self, received: Received) -> None:
        try:
            text = received.decode().data
        except Exception:  # a peer's bytes that are not a String: not a hello
            return
        if isinstance(text, str):
            self.heard(self.subscribed, text)

    def failed(self, text: str) -> None:
        self.error = text

    def take(self) -> dict[str, Any]:
        """This period's counts, and a fresh period."""
        with self.lock:
            taken = {"published": self.published, "subscribed_from": self.subscribed,
                     "sent": self.sent, "received_from": self.received}  # fmt: skip
            self.published = self.sent = 0
            self.subscribed, self.received = {}, {}
        return taken


def _table(counts: dict[str, int], period: float) -> list[str]:
    rows = [("Hostname", f"Msg Count /{period}s"), *counts.items()]
    return [f"{'':<15} {name:<20} {count:<10}" for name, count in rows]


def summary_text(topic: str, period: float, counts: dict[str, Any]) -> str:
    """ros2 doctor hello's table, line for line (its padding included)."""
    lines = [
        "MULTIMACHINE COMMUNICATION SUMMARY",
        f"Topic: {topic}, Published Msg Count: {counts['published']}",
        "Subscribed from:",
        *_table(counts["subscribed_from"], period),
        f"Multicast Group/Port: {GROUP}/{PORT}, Sent Msg Count: {counts['sent']}",
        "Received from:",
        *_table(counts["received_from"], period),
        RULE,
    ]
    return "\n".join(lines)


def _listen(sock: socket.socket, tally: Tally, stop: threading.Event) -> None:
    sock.settimeout(0.2)
    while not stop.is_set():
        try:
            data = sock.recv(4096)
        except TimeoutError:
            continue
        except OSError:
            return
        tally.heard(tally.received, data.decode("utf-8", errors="replace"))


@click.command(
    "hello",
    epilog="""\b
Examples:
  rostool doctor hello                      # on the laptop and on the robot, Ctrl+C to stop
  MULTIMACHINE COMMUNICATION SUMMARY
  Topic: /canyouhearme, Published Msg Count: 10
  Subscribed from:
                  Hostname             Msg Count /1.0s
                  robot                10
  Multicast Group/Port: 225.0.0.1/49150, Sent Msg Count: 10
  Received from:
                  Hostname             Msg Count /1.0s
                  robot                10
  ------------------------------------------------------------
  rostool doctor hello -n 50 --json         # 50 hellos (5 s), then exit; a JSON object per summary
  rostool doctor hello -t /ping -ep 0.5 -pp 5 --ttl 4
""",
)
@click.option("-t", "--topic", default="/canyouhearme", show_default=True,
              help="The topic to publish hellos to and hear them on (std_msgs String).")  # fmt: skip
@click.option("-ep", "--emit-period", type=click.FloatRange(0, min_open=True), default=0.1, show_default=True,
              metavar="S", help="Seconds between two hellos (each published and sent).")  # fmt: skip
@click.option("-pp", "--print-period", type=click.FloatRange(0, min_open=True), default=1.0,
              show_default=True, metavar="S", help="Seconds between two summary tables.")  # fmt: skip
@click.option("--ttl", type=click.IntRange(1, 255), metavar="N",
              help="The multicast TTL (default: the system's, 1).")  # fmt: skip
@click.option("-1", "--once", is_flag=True, help="One hello, one emit period, one summary, then exit.")
@click.option("-n", "--emits", type=click.IntRange(min=1), metavar="N",
              help="N hellos, then the last period's summary and exit (default: until Ctrl+C).")  # fmt: skip
@json_option
@click.pass_context
def hello(
    ctx: click.Context, topic: str, emit_period: float, print_period: float, ttl: int | None, once: bool,
    emits: int | None, as_json: bool,
) -> None:  # fmt: skip
    """Check that machines hear each other on a topic and by multicast (ros2 doctor hello).

    Run it on each machine. Every emit period it publishes "hello, it's me <host name>" on the topic and
    sends the same text by UDP multicast (225.0.0.1, port 49150, as `rostool multicast`); every print period
    it prints how many it published and sent, and which other hosts it heard, on the topic and by
    multicast. A host heard by multicast but not on the topic: their ROS settings differ (domain, discovery
    range, master); heard on neither: multicast does not pass between them (a router: ROS 2 then needs
    ROS_STATIC_PEERS).
    """
    from rostool.graph import open_graph

    host = socket.gethostname()
    tally = Tally(host)
    node = "rostool_doctor_" + re.sub(r"[^0-9a-zA-Z_]", "_", host)
    with joined_socket(GROUP, PORT) as listening, sending_socket(GROUP, ttl) as sending:
        stop = threading.Event()
        listener = threading.Thread(target=_listen, args=(listening, tally, stop), daemon=True)
        listener.start()
        graph = open_graph(ros_version(ctx), node, (), ros2_backend(ctx), use_daemon=False)
        try:
            type_name = "std_msgs/msg/String" if graph.style == "ros2" else "std_msgs/String"
            publisher = graph.publisher(topic, type_name)
            message = graph.build_message(type_name, {"data": GREETING + host})
            graph.subscribe(topic, tally.on_message, tally.failed)
            datagram = (GREETING + host).encode()

            def emit() -> None:
                with tally.lock:
                    tally.published += 1
                publisher.publish(message)
                send_datagram(sending, datagram, GROUP, PORT)
                with tally.lock:
                    tally.sent += 1

            def show() -> None:
                counts = tally.take()
                if as_json:
                    print_json({"topic": graph.resolve(topic), "group": GROUP, "port": PORT,
                                "period": print_period, **counts})  # fmt: skip
                else:
                    click.echo(summary_text(topic, print_period, counts))

            _emit_loop(emit, show, tally, emit_period, print_period, 1 if once else emits)
        finally:
            stop.set()
            graph.close()
            listener.join(1.0)


def _emit_loop(
    emit: Callable[[], None], show: Callable[[], None], tally: Tally, emit_period: float, print_period: float,
    emits: int | None,
) -> None:  # fmt: skip
    """ros2's loop: a summary once a print period has passed, then a hello, then the rest of the emit period
    (each hello has its own due time, so the period never drifts); after the last hello, its period and
    the last summary. What was heard before the first hello (while the graph opened) counts for no period."""
    tally.take()
    start = last_print = time.monotonic()
    emitted = 0
    while True:
        now = time.monotonic()
        if now - last_print > print_period:
            show()
            last_print = now
        if tally.error is not None:
            raise RostoolError(tally.error)
        emit()
        emitted += 1
        time.sleep(max(0.0, start + emitted * emit_period - time.monotonic()))
        if emits is not None and emitted >= emits:
            show()
            return
