"""`rostool bag reindex`: rebuild the index of a bag cut short."""

from __future__ import annotations

import click

from rostool.commands.bag._options import CONTEXT


@click.command(context_settings=CONTEXT)
@click.argument("files", nargs=-1, required=True, metavar="FILE...")
def reindex(files: tuple[str, ...]) -> None:
    """Rebuild the index of a ROS 1 .bag, the summary of an .mcap, or a rosbag2 directory cut short.

    Every message that reached the disk is kept, also those of a half-written last chunk. The original
    file is kept as NAME.orig.bag (NAME.orig.mcap), as `rosbag reindex` does. A rosbag2 directory left by
    a killed recorder (NAME.mcap.active/, NAME.db3.active/, or a `ros2 bag record` directory without
    metadata.yaml) gets its .mcap files repaired, its .db3 rolled back to the last commit and metadata.yaml
    rebuilt; the originals are kept in DIR.orig/.

    \b
    Examples:
      rostool bag reindex crashed.bag
      rostool bag reindex crashed.mcap
      rostool bag reindex run.mcap.active
    """
    from rostool.bag.reindex import reindex as rebuild

    for path in files:
        result = rebuild(path)
        extra = " (some from a half-written last chunk)" if result.partial else ""
        click.echo(
            f"{result.path}: {result.messages} messages indexed{extra}; original kept as {result.backup}"
        )
