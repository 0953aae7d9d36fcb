"""ros2 bag record's flags as parsed (`RecordFlags`), its validate_parsed_arguments, message for message, and
the topic rules they make."""

from __future__ import annotations

from dataclasses import dataclass

import click

from rostool.bag.record_select import HIDDEN, TopicRules, compile_pattern, services_events
from rostool.commands.bag._options import topic_list
from rostool.errors import RostoolError
from rostool.graph.qos import QosRequest


@dataclass(frozen=True)
class RecordFlags:
    positional_topics: tuple[str, ...]
    output: str | None
    storage: str
    topics: tuple[str, ...]
    services: tuple[str, ...]
    topic_types: tuple[str, ...]
    all_: bool
    all_topics: bool
    all_services: bool
    regex: str
    exclude_regex: str
    exclude_topics: tuple[str, ...]
    exclude_topic_types: tuple[str, ...]
    exclude_services: tuple[str, ...]
    include_hidden_topics: bool
    include_unpublished_topics: bool
    no_discovery: bool
    polling_interval: int
    qos_profile_overrides_path: str | None
    serialization_format: str
    max_bag_size: int
    max_bag_duration: int
    max_bag_files: int
    max_cache_size: int
    compression_mode: str
    compression_format: str
    use_sim_time: bool
    node_name: str
    custom_data: tuple[str, ...]
    disable_keyboard_controls: bool
    log_level: str
    duration: float | None
    quiet: bool
    output_name: str | None
    force: bool
    compression_queue_size: int
    compression_threads: int
    compression_threads_priority: int
    max_cache_duration: int
    start_paused: bool
    snapshot_mode: bool
    ignore_leaf_topics: bool
    static_topics_path: str | None
    storage_preset_profile: str | None
    storage_config_file: str | None
    max_rate: tuple[str, ...]
    progress: float
    interface_paths: tuple[str, ...]
    qos: QosRequest

    @property
    def topic_names(self) -> list[str]:
        return topic_list([*self.positional_topics, *self.topics])

    @property
    def recording_all_topics(self) -> bool:
        return self.all_ or self.all_topics

    @property
    def recording_all_services(self) -> bool:
        return self.all_ or self.all_services

    @property
    def hidden_topics_needed(self) -> bool:
        """Asked for, or services (their event topics are hidden), or -e, or a hidden name in --topics."""
        needed = self.include_hidden_topics or bool(topic_list(self.services)) or self.recording_all_services
        return needed or bool(self.regex) or any(HIDDEN.search(t) for t in self.topic_names)


def check_flags(flags: RecordFlags) -> None:
    """Refuse what rostool cannot do and what ros2 bag refuses; warn where ros2 bag warns."""
    topics, services, topic_types = (
        flags.topic_names,
        topic_list(flags.services),
        topic_list(flags.topic_types),
    )
    all_topics, all_services, regex = flags.recording_all_topics, flags.recording_all_services, flags.regex
    static = flags.static_topics_path
    if not (all_topics or all_services or topics or services or topic_types or regex or static):
        raise RostoolError(  # rosbag2's own line, its missing space too
            "Need to specify at least one option out of --all, --all-topics, --all-services, --services, "
            "--topics, --topic-types,--static-topics-path or --regex"
        )
    if flags.exclude_regex and not (all_topics or all_services or topic_types or regex):
        raise RostoolError(
            "--exclude-regex argument requires either --all, --all-topics, --topic-types, "
            "--all-services or --regex"
        )
    if flags.exclude_topics and not (all_topics or topic_types or regex):
        raise RostoolError(
            "--exclude-topics argument requires either --all, --all-topics, --topic-types or --regex"
        )
    if flags.exclude_topic_types and not (all_topics or topic_types or regex):
        raise RostoolError("--exclude-topic-types argument requires either --all, --all-topics or --regex")
    if flags.exclude_services and not (all_services or regex):
        raise RostoolError("--exclude-services argument requires either --all, --all-services or --regex")
    if flags.use_sim_time and flags.no_discovery:
        raise RostoolError(
            "--use-sim-time and --no-discovery both set, but are incompatible settings: "
            "the /clock topic needs to be discovered to record with sim time"
        )
    if flags.compression_format and flags.compression_mode == "none":
        raise RostoolError("Invalid choice: Cannot specify compression format without a compression mode.")
    if flags.snapshot_mode and flags.max_cache_size == 0 and not flags.max_cache_duration:
        raise RostoolError(
            "In snapshot mode, either the max_cache_duration or max_cache_size shall not be set to zero."
        )  # rosbag2's own line
    if flags.max_bag_files and not (flags.max_bag_size or flags.max_bag_duration):
        raise RostoolError("--max-bag-files needs --max-bag-size or --max-bag-duration")
    warn = [
        (all_services and services, "--all or --all-services will override --services"),
        (all_topics and topics, "--all or --all-topics will override --topics"),
        (
            (all_topics or all_services) and regex,
            "--all, --all-topics or --all-services will override --regex",
        ),
    ]
    for given, text in warn:
        if given:
            click.echo(f"[WARN] [ros2bag]: {text}", err=True)


def static_topics(flags: RecordFlags, rules: TopicRules) -> dict[str, str]:
    """--static-topics-path's topics and types, but those the exclusions of `rules` leave out (as rosbag2
    applies them above its static list): -x, --exclude-topics, --exclude-topic-types."""
    if flags.static_topics_path is None:
        return {}
    from rostool.bag.static_topics import load_static_topics
    from rostool.interfaces.names import to_store_name

    def absolute(name: str) -> str:  # relative names are under the root namespace, as the recorder's own
        return name if name.startswith(("/", "~")) else "/" + name

    exclude_regex = rules.exclude_regex
    exclude_topics = {absolute(t) for t in rules.exclude_topics}
    exclude_types = {to_store_name(t) for t in rules.exclude_types}
    kept = {}
    for topic, type_name in load_static_topics(flags.static_topics_path).items():
        name = absolute(topic)
        excluded = name in exclude_topics or to_store_name(type_name) in exclude_types
        if not excluded and not (exclude_regex is not None and exclude_regex.search(name)):
            kept[topic] = type_name
    return kept


def discovers(flags: RecordFlags) -> bool:
    """Whether topics are looked for at all: only static topics are subscribed once and never looked for,
    as rosbag2 turns its discovery off then."""
    lists = (flags.topic_names, topic_list(flags.services), topic_list(flags.topic_types))
    return flags.recording_all_topics or flags.recording_all_services or bool(flags.regex) or any(lists)


def topic_rules(flags: RecordFlags) -> TopicRules:
    """Which topics and services to record (the regular expressions compiled: a bad one is one line)."""
    return TopicRules(
        topics=frozenset(flags.topic_names),
        services=services_events(topic_list(flags.services)),
        topic_types=frozenset(topic_list(flags.topic_types)),
        all_topics=flags.recording_all_topics,
        all_services=flags.recording_all_services,
        regex=compile_pattern(flags.regex, "-e/--regex"),
        exclude_regex=compile_pattern(flags.exclude_regex, "-x/--exclude-regex"),
        exclude_topics=frozenset(topic_list(flags.exclude_topics)),
        exclude_types=frozenset(topic_list(flags.exclude_topic_types)),
        exclude_services=services_events(topic_list(flags.exclude_services)),
        hidden=flags.include_hidden_topics,
        ignore_leaf=flags.ignore_leaf_topics,
    )
