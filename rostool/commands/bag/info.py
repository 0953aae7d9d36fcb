"""`rostool bag info`: summarize bags from their index."""

from __future__ import annotations

from functools import partial
from typing import Any

import click

from rostool.bag.many import BagItem
from rostool.commands.bag._options import CONTEXT, jobs_option
from rostool.errors import RostoolError


@click.command(context_settings=CONTEXT)
@click.argument("bags", nargs=-1, required=True, metavar="BAG...")
@click.option("--json", "as_json", is_flag=True, help="One JSON object (a list for several bags).")
@click.option("--yaml", "as_yaml", is_flag=True, help="YAML with `rosbag info --yaml`'s keys.")
@click.option("--freq", is_flag=True, help="Also show each topic's rate (reads message timestamps).")
@click.option("-t", "--topic-name", is_flag=True, help="Only the topic names, one a line (ros2 bag info -t).")
@click.option(
    "--sort",
    type=click.Choice(["name", "type", "count"]),
    help="Topics (and services) ascending by name, type or message count (ros2 bag info --sort).",
)
@click.option("-v", "--verbose", is_flag=True,
              help="rosbag2 bags: also count each service's requests and responses.")  # fmt: skip
@jobs_option
def info(
    bags: tuple[str, ...], as_json: bool, as_yaml: bool, freq: bool, topic_name: bool, sort: str | None,
    verbose: bool, jobs: int | None,
) -> None:  # fmt: skip
    """Summarize bags from their index: duration, size, counts, types and topics.

    Several bags, or a directory of bags (searched recursively; a rosbag2 directory is one bag), are
    read in parallel processes and printed in order.

    \b
    Examples:
      rostool bag info run.bag
      rostool bag info rosbag2_dir/ --json | jq '.topics[] | select(.count > 0) | .name'
      rostool bag info a.bag b.mcap --yaml
      rostool bag info fleet/ -j 2 --json
      rostool bag info rosbag2_dir/ -t                # topic names only, as ros2 bag info -t
      rostool bag info run.mcap --sort count          # fewest messages first, as ros2 bag info --sort
    """
    from rostool.bag.info import format_text, sort_topics, to_rosbag_yaml
    from rostool.bag.many import expand, successes

    if as_json and as_yaml:
        raise RostoolError("choose one of --json and --yaml")
    items = expand(bags)
    infos = [value for _item, value in successes(partial(_info_one, freq), items, jobs, "reading")]
    for one in infos if sort else ():
        sort_topics(one, sort)
    if as_json:
        from rostool.output.json_text import dumps

        click.echo(dumps(infos[0].to_dict() if len(infos) == 1 else [i.to_dict() for i in infos]))
    elif as_yaml:
        import yaml

        data = [to_rosbag_yaml(i) for i in infos]
        click.echo(yaml.safe_dump(data[0] if len(data) == 1 else data, sort_keys=False).rstrip("\n"))
    else:
        separator = "\n" if topic_name else "\n\n"
        click.echo(
            separator.join(format_text(i, verbose=verbose, topic_name=topic_name, sort=sort) for i in infos)
        )


def _info_one(freq: bool, item: BagItem) -> Any:
    from rostool.bag.info import bag_info

    return bag_info(item.path, freq=freq)
