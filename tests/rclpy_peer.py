"""A real ROS 2 node on rclpy, run with a peer venv's python (Jazzy or Kilted, Fast DDS): the referee of
every ROS 2 test. It takes roles from its arguments and reports what it sees as JSON lines on stdout:

    {"event": "ready"}                                   after every entity is created
    {"event": "heard", "topic": T, "data": ...}          --listen: each message (std_msgs/String data)
    {"event": "service", "data": true}                   --service: each std_srvs/SetBool request
                                                         (--setbool-introspect too: its own client's)
    (no events)                                          --echo-service: test_msgs/BasicTypes echo
    {"event": "goal", "order": 5} / "cancel" / "done"    --action: test_msgs/Fibonacci server
    {"event": "param", "name": N, "value": V}            --params: each accepted parameter change
    {"event": "graph", ...}                              --watch: this node's view of the graph
    {"event": "published", "count": N, "t": T}           --talk: about once a second (monotonic time)
    {"event": "stamped", "count": N, "t": T}             --stamped: about once a second
    {"event": "matched", "topic": T, "subscribers": N, "count": N, "t": T, "progress": KIND}
                                                         --talk, --stamped: its subscriber count changed
                                                         (count: published so far, as KIND events count)
    {"event": "sent", "count": N, "seconds": S}          --talk with --count: after the burst
    {"event": "counted", "count": N, "first": T, "last": T}  --raw-count: every 0.5 s
    (no events)                                          --repeat TYPE=TOPIC: default TYPE messages at 1 Hz
                                                         --hello TOPIC: 'Hello World: N' at 1 Hz
                                                         --cmd-vel TOPIC: TwistStamped, stamp now, linear.x 1
                                                         (--period S: every S seconds instead)
    (no events)                                          --extra-nodes N: N more nodes after this one,
                                                         NAME_1..NAME_N, each publishing std_msgs/String
                                                         on /NAME_i/t0.. (--extra-topics K of them)

Not a pytest module: tests start it through tests/ros2_peers.py.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import threading
import time

import rclpy
from rclpy.action import ActionServer, CancelResponse
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

_print_lock = threading.Lock()

EVERY_TYPE = {
    "flag": True,
    "count": 3,
    "speed": 0.5,
    "label": "r2",
    "blob": [b"\x01", b"\x02"],  # rclpy takes a byte array as a list of single bytes
    "switches": [True, False],
    "ids": [1, 2, 3],
    "gains": [0.1, 0.2],
    "names": ["a", "b"],
}
# --ros2cli-params: the parameters of ros2cli's ros2param fixtures (test/param_node.py and
# test/fixtures/parameter_node.py); None is declared with dynamic typing (a "not set" parameter)
ROS2CLI_PARAMS = {
    "param_node": {
        "bool_param": True, "int_param": 42, "double_param": 1.23, "str_param": "Hello World",
        "int_array": [1, 2, 3], "double_array": [1.0, 2.0, 3.0], "bool_array": [True, False, True],
        "str_array": ["Hello", "World"], "byte_array": [b"p", b"v"], "parameter_with_no_value": None,
    },
    "parameter_node": {
        "bool_param": True, "int_param": 42, "double_param": 1.23, "str_param": "Hello World",
        "bool_array_param": [False, False, True], "int_array_param": [1, 2, 3],
        "str_array_param": ["foo", "bar", "baz"], "double_array_param": [3.125, 6.25, 12.5],
        "foo.str_param": "foo", "foo.bar.str_param": "foobar",
    },
}  # fmt: skip


def emit(event: str, **fields: object) -> None:
    with _print_lock:
        sys.stdout.write(json.dumps({"event": event, **fields}, default=repr) + "\n")
        sys.stdout.flush()


def plain(value: object) -> object:
    if isinstance(value, (bytes, bytearray)):
        return list(value)
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    return value


class Peer(Node):
    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__(args.name, namespace=args.namespace)
        self.count = args.first - 1
        self.reported = time.monotonic()
        self.subscribers: dict[object, int] = {}
        self.rate = args.rate
        self.stamped_reported = time.monotonic()
        if args.talk:
            from std_msgs.msg import String

            qos = QoSProfile(depth=args.depth)
            if args.best_effort:
                qos.reliability = ReliabilityPolicy.BEST_EFFORT
            if args.latched:
                qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
            self.publisher = self.create_publisher(String, args.talk, qos)
            self.message = String()
            if args.count:
                threading.Thread(target=self.burst, args=(args,), daemon=True).start()
            else:
                self.create_timer(1.0 / args.rate, self.tick)
        if args.stamped:
            from geometry_msgs.msg import PointStamped

            self.stamped = self.create_publisher(PointStamped, args.stamped, 10)
            self.point = PointStamped()
            self.point.header.frame_id = "map"
            self.create_timer(1.0 / args.rate, self.tick_stamped)
        if args.raw_count:
            from std_msgs.msg import String

            self.counted = 0
            self.first = self.last = 0.0
            qos = QoSProfile(depth=args.depth)
            self.create_subscription(String, args.raw_count, self.on_raw, qos, raw=True)
            self.create_timer(0.5, self.report_count)
        for topic in args.listen:
            from std_msgs.msg import String

            self.create_subscription(
                String, topic, lambda m, t=topic: emit("heard", topic=t, data=m.data), 10
            )
        if args.params:
            for name, value in EVERY_TYPE.items():
                self.declare_parameter(name, value)
            self.add_post_set_parameters_callback(self.on_params)
        if args.ros2cli_params:
            from rcl_interfaces.msg import ParameterDescriptor

            for name, value in ROS2CLI_PARAMS[args.ros2cli_params].items():
                self.declare_parameter(name, value, ParameterDescriptor(dynamic_typing=value is None))
        if args.service:
            from std_srvs.srv import SetBool

            self.create_service(SetBool, args.service, self.on_set_bool)
        if args.echo_service:  # as ros2cli's echo_server fixture: the request's fields back as the response
            from test_msgs.srv import BasicTypes

            echo = self.create_service(BasicTypes, args.echo_service, self.on_echo)
            if args.introspect:  # as ros2cli's introspectable fixture: contents on, a client calling
                from rclpy.qos import qos_profile_system_default
                from rclpy.service_introspection import ServiceIntrospectionState

                contents = (self.get_clock(), qos_profile_system_default, ServiceIntrospectionState.CONTENTS)
                echo.configure_introspection(*contents)
                self.echo_client = self.create_client(BasicTypes, args.echo_service)
                self.echo_client.configure_introspection(*contents)
                self.echo_future: object = None
                self.create_timer(0.5, self.call_echo)
        if args.action:
            from test_msgs.action import Fibonacci

            self.fibonacci = Fibonacci
            self.step = args.step
            ActionServer(self, Fibonacci, args.action, self.on_goal, cancel_callback=self.on_cancel)
        if args.watch:
            self.create_timer(0.5, self.report_graph)
        for spec in args.repeat:  # as ros2cli's repeater fixture: a default-constructed message each second
            import importlib

            type_name, _, topic = spec.partition("=")
            package, _, name = type_name.split("/")
            cls = getattr(importlib.import_module(f"{package}.msg"), name)
            publisher = self.create_publisher(cls, topic, 10)
            self.create_timer(args.period, lambda p=publisher, c=cls: p.publish(c()))
        if args.hello:
            from std_msgs.msg import String

            self.hello = self.create_publisher(String, args.hello, 10)
            self.hello_count = 0
            self.create_timer(args.period, self.tick_hello)
        if args.cmd_vel:
            from geometry_msgs.msg import TwistStamped

            self.cmd_vel = self.create_publisher(TwistStamped, args.cmd_vel, 10)
            self.create_timer(args.period, self.tick_cmd_vel)
        if args.setbool_introspect:
            self.introspect_set_bool(args.setbool_introspect)

    def tick_hello(self) -> None:
        from std_msgs.msg import String

        self.hello_count += 1
        self.hello.publish(String(data=f"Hello World: {self.hello_count}"))

    def tick_cmd_vel(self) -> None:
        from geometry_msgs.msg import TwistStamped

        message = TwistStamped()
        message.header.stamp = self.get_clock().now().to_msg()
        message.twist.linear.x = 1.0
        self.cmd_vel.publish(message)

    def report_matched(self, publisher: object, count: int, progress: str) -> None:
        """A "matched" event when the publisher's subscriber count changed: tests wait on it for a
        recorder or an echo to be listening, instead of sleeping."""
        subscribers = publisher.get_subscription_count()  # type: ignore[attr-defined]
        if subscribers != self.subscribers.get(publisher, 0):
            self.subscribers[publisher] = subscribers
            topic = publisher.topic_name  # type: ignore[attr-defined]
            emit(
                "matched",
                topic=topic,
                subscribers=subscribers,
                count=count,
                t=time.monotonic(),
                progress=progress,
            )

    def tick(self) -> None:
        self.count += 1
        self.message.data = f"hello {self.count}"
        self.publisher.publish(self.message)
        if self.count % 20 == 1 or self.rate <= 50:  # at most ~50 checks a second, even at 1 kHz
            self.report_matched(self.publisher, self.count, "published")
        now = time.monotonic()
        if now - self.reported >= 1.0:
            self.reported = now
            emit("published", count=self.count, t=now)

    def burst(self, args: argparse.Namespace) -> None:
        """--count N: once --subs subscribers matched, N messages at --rate (0: as fast as possible)."""
        while self.publisher.get_subscription_count() < args.subs:
            time.sleep(0.005 if args.at_once else 0.05)
        if not args.at_once:
            time.sleep(1.0)
        period = 1.0 / args.rate if args.rate else 0.0
        start = time.perf_counter()
        for i in range(args.count):
            if period:
                delay = start + i * period - time.perf_counter()
                if delay > 0:
                    time.sleep(delay)
            self.message.data = f"hello {i}"
            self.publisher.publish(self.message)
        emit("sent", count=args.count, seconds=time.perf_counter() - start)

    def on_raw(self, _payload: bytes) -> None:
        now = time.monotonic()
        if not self.counted:
            self.first = now
        self.counted += 1
        self.last = now

    def report_count(self) -> None:
        emit("counted", count=self.counted, first=self.first, last=self.last)

    def tick_stamped(self) -> None:
        self.point.header.stamp = self.get_clock().now().to_msg()
        self.point.point.x += 1.0
        self.stamped.publish(self.point)
        count = int(self.point.point.x)
        self.report_matched(self.stamped, count, "stamped")
        now = time.monotonic()
        if now - self.stamped_reported >= 1.0:
            self.stamped_reported = now
            emit("stamped", count=count, t=now)

    def on_params(self, parameters: list) -> None:
        for parameter in parameters:
            emit("param", name=parameter.name, value=plain(parameter.value))

    def on_set_bool(self, request: object, response: object) -> object:
        emit("service", data=request.data)  # type: ignore[attr-defined]
        response.success = bool(request.data)  # type: ignore[attr-defined]
        response.message = f"flag is {request.data}"  # type: ignore[attr-defined]
        return response

    def on_echo(self, request: object, response: object) -> object:
        for field in request.get_fields_and_field_types():  # type: ignore[attr-defined]
            setattr(response, field, getattr(request, field))
        return response

    def call_echo(self) -> None:
        from test_msgs.srv import BasicTypes

        done = self.echo_future is None or self.echo_future.done()  # type: ignore[attr-defined]
        if self.echo_client.service_is_ready() and done:
            request = BasicTypes.Request(bool_value=True, int32_value=42, string_value="test_string_value")
            self.echo_future = self.echo_client.call_async(request)

    def on_cancel(self, _goal: object) -> CancelResponse:
        emit("cancel")
        return CancelResponse.ACCEPT

    def on_goal(self, goal: object) -> object:
        order = goal.request.order  # type: ignore[attr-defined]
        emit("goal", order=order)
        sequence = [0, 1]
        feedback = self.fibonacci.Feedback()
        for _ in range(1, order):
            if goal.is_cancel_requested:  # type: ignore[attr-defined]
                goal.canceled()  # type: ignore[attr-defined]
                emit("canceled")
                result = self.fibonacci.Result()
                result.sequence = sequence
                return result
            sequence.append(sequence[-1] + sequence[-2])
            feedback.sequence = sequence
            goal.publish_feedback(feedback)  # type: ignore[attr-defined]
            time.sleep(self.step)
        goal.succeed()  # type: ignore[attr-defined]
        emit("done", sequence=sequence)
        result = self.fibonacci.Result()
        result.sequence = sequence
        return result

    def introspect_set_bool(self, service: str) -> None:
        """--setbool-introspect: a std_srvs/SetBool server and a client calling it every 0.5 s (data
        True, False, True, ...), both with introspection CONTENTS, as a user's node would configure it."""
        from rclpy.qos import qos_profile_system_default
        from rclpy.service_introspection import ServiceIntrospectionState
        from std_srvs.srv import SetBool

        contents = (self.get_clock(), qos_profile_system_default, ServiceIntrospectionState.CONTENTS)
        server = self.create_service(SetBool, service, self.on_set_bool)
        server.configure_introspection(*contents)
        self.set_bool_client = self.create_client(SetBool, service)
        self.set_bool_client.configure_introspection(*contents)
        self.set_bool_future: object = None
        self.set_bool_calls = 0
        self.create_timer(0.5, self.call_set_bool)

    def call_set_bool(self) -> None:
        from std_srvs.srv import SetBool

        done = self.set_bool_future is None or self.set_bool_future.done()  # type: ignore[attr-defined]
        if self.set_bool_client.service_is_ready() and done:
            self.set_bool_calls += 1
            request = SetBool.Request(data=self.set_bool_calls % 2 == 1)
            self.set_bool_future = self.set_bool_client.call_async(request)

    def report_graph(self) -> None:
        topics = dict(self.get_topic_names_and_types())
        publishers = {
            topic: sorted(
                (info.node_namespace.rstrip("/") + "/" + info.node_name)
                for info in self.get_publishers_info_by_topic(topic)
            )
            for topic in topics
        }
        subscribers = {
            topic: sorted(
                (info.node_namespace.rstrip("/") + "/" + info.node_name)
                for info in self.get_subscriptions_info_by_topic(topic)
            )
            for topic in topics
        }
        nodes = sorted(ns.rstrip("/") + "/" + n for n, ns in self.get_node_names_and_namespaces())
        emit("graph", nodes=nodes, topics=topics, publishers=publishers, subscribers=subscribers)


def extra_nodes(args: argparse.Namespace) -> list[Node]:
    """--extra-nodes: more nodes of this process's one context, made one after the other as a launch
    file's composed nodes are (the last one's publishers are the last entities the participant makes)."""
    from std_msgs.msg import String

    made = []
    for i in range(1, args.extra_nodes + 1):
        extra = Node(f"{args.name}_{i}", namespace=args.namespace)
        for t in range(args.extra_topics):
            extra.create_publisher(String, f"/{args.name}_{i}/t{t}", 10)
        made.append(extra)
    return made


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--name", default="peer")
    parser.add_argument("--namespace", default="")
    parser.add_argument("--talk", help="publish std_msgs/String 'hello N' on this topic")
    parser.add_argument("--first", type=int, default=1, help="with --talk: N of the first 'hello N' (1000: "
                        "every text keeps its length for half an hour at 5 Hz)")  # fmt: skip
    parser.add_argument("--stamped", help="publish geometry_msgs/PointStamped (stamp = now, x = 1, 2, ...)")
    parser.add_argument("--rate", type=float, default=10.0)
    parser.add_argument("--depth", type=int, default=10)
    parser.add_argument("--best-effort", action="store_true")
    parser.add_argument("--latched", action="store_true")
    parser.add_argument("--count", type=int, help="with --talk: publish N messages, then idle")
    parser.add_argument("--subs", type=int, default=1, help="with --count: subscribers to wait for")
    parser.add_argument(
        "--at-once", action="store_true", help="with --count: publish the moment they matched (no 1 s pause)"
    )
    parser.add_argument("--raw-count", help="count std_msgs/String here (raw=True, as ros2 topic hz)")
    parser.add_argument("--listen", action="append", default=[])
    parser.add_argument("--params", action="store_true", help="declare a parameter of every type")
    parser.add_argument(
        "--ros2cli-params",
        choices=sorted(ROS2CLI_PARAMS),
        help="declare the parameters of that ros2cli ros2param test fixture",
    )
    parser.add_argument("--service", help="serve std_srvs/srv/SetBool here")
    parser.add_argument("--echo-service", help="serve test_msgs/srv/BasicTypes here, echoing the request")
    parser.add_argument(
        "--introspect",
        action="store_true",
        help="with --echo-service: introspection contents on, and a client calling it",
    )
    parser.add_argument("--action", help="serve test_msgs/action/Fibonacci here")
    parser.add_argument("--step", type=float, default=0.1, help="seconds between Fibonacci feedbacks")
    parser.add_argument("--watch", action="store_true", help="report the graph every 0.5 s")
    parser.add_argument(
        "--repeat",
        action="append",
        default=[],
        metavar="TYPE=TOPIC",
        help="publish a default pkg/msg/Type message on TOPIC every second",
    )
    parser.add_argument("--hello", help="publish std_msgs/String 'Hello World: N' here at 1 Hz")
    parser.add_argument("--cmd-vel", help="publish geometry_msgs/TwistStamped (stamp now, x 1) at 1 Hz")
    parser.add_argument("--period", type=float, default=1.0, help="seconds between --repeat, --hello and "
                        "--cmd-vel messages (ros2cli's fixtures: 1)")  # fmt: skip
    parser.add_argument("--setbool-introspect", metavar="SERVICE", help="serve std_srvs/srv/SetBool here "
                        "with introspection contents on, and a client calling it every 0.5 s")  # fmt: skip
    parser.add_argument("--extra-nodes", type=int, default=0, help="N more nodes in this process, created "
                        "after this one: NAME_1..NAME_N, each publishing on /NAME_i/t0..")  # fmt: skip
    parser.add_argument("--extra-topics", type=int, default=3, help="with --extra-nodes: publishers per node")
    args = parser.parse_args()
    rclpy.init()
    node = Peer(args)
    # the counter runs as `ros2 topic hz` does (one thread); the servers need several
    executor = SingleThreadedExecutor() if args.raw_count else MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    for extra in extra_nodes(args):
        executor.add_node(extra)
    emit("ready", node=node.get_fully_qualified_name())
    with contextlib.suppress(KeyboardInterrupt, ExternalShutdownException):
        executor.spin()


if __name__ == "__main__":
    main()
