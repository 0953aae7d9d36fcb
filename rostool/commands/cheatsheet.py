"""`rostool cheatsheet`: the ROS 1 / ROS 2 / rostool command reference, searchable."""

from __future__ import annotations

import sys
from typing import cast

import click

from rostool.errors import RostoolError

FORMATS = ("table", "text", "markdown", "json")


@click.command(
    "cheatsheet",
    # Unknown options stay in QUERY, so `rostool cheatsheet rosbag play -l` needs no quotes.
    context_settings={"ignore_unknown_options": True},
    epilog="""\b
Examples:
  rostool cheatsheet                          the whole reference, by section
  rostool cheatsheet roscpp list              search (the book's misspellings are corrected)
  rostool cheatsheet loop
  rostool cheatsheet rospy.Rate --format json
  rostool cheatsheet --section bags --format markdown
  rostool cheatsheet --ros2 "ros2 topic hz"   which ROS 1 / rostool command is this?
  rostool cheatsheet --ros2 ros2 param get    rostool's ROS 2 form first (rostool --ros2 ...)
""",
)
@click.argument("query", nargs=-1, type=click.UNPROCESSED)
@click.option("--section", metavar="SECTION", help="Only this section (nodes, topics, params, bags, ...).")
@click.option(
    "--format",
    "output_format",
    type=click.Choice(FORMATS),
    help="Output format. Default: a table on a terminal, plain text when piped.",
)
@click.option(
    "--ros2",
    "ros2_column",
    is_flag=True,
    help="Treat QUERY as a ROS 2 command or rclpy call; show rostool's ROS 2 form first.",
)
@click.option(
    "--limit", type=click.IntRange(min=0), default=10, show_default=True, help="Most hits shown (0: all)."
)
def cheatsheet(
    query: tuple[str, ...], section: str | None, output_format: str | None, ros2_column: bool, limit: int
) -> None:
    """Show or search the ROS 1 / ROS 2 / rostool command reference.

    Without QUERY, prints every entry grouped by section. With QUERY, shows the best matches first;
    typos are tolerated and the book's misspelled commands (roscpp list, rosvbag info...) lead to the
    right command with a note.
    """
    from rostool.reference import default_reference, search
    from rostool.reference.model import live_command_groups
    from rostool.reference.render import Block, print_table, render_json, render_markdown, render_text

    root = cast(click.Group, click.get_current_context().find_root().command)
    reference = default_reference(live_command_groups(root))
    section_id = reference.section(section).id if section else None
    text = " ".join(query).strip()
    if ros2_column and not text:
        raise RostoolError(
            "--ros2 needs a QUERY, e.g. rostool cheatsheet --ros2 'ros2 topic hz'", exit_code=2
        )

    notes: tuple[str, ...] = ()
    if text:
        result = search(
            reference, text, column="ros2" if ros2_column else "ros1", section=section_id, limit=limit
        )
        if not result.hits:
            where = f" in section '{section_id}'" if section_id else ""
            raise RostoolError(
                f"no cheatsheet entry matches '{text}'{where}; try fewer words, or run 'rostool cheatsheet'"
            )
        notes = result.notes
        blocks = [Block(None, result.entries)]
    else:
        sections = [reference.section(section_id)] if section_id else list(reference.sections)
        blocks = [Block(item.title, item.entries) for item in sections]

    titles = {item.id: item.title for item in reference.sections}
    primary = "ros2" if ros2_column else "ros1"
    chosen = output_format or ("table" if sys.stdout.isatty() else "text")
    if chosen == "json":
        for note in notes:
            click.echo(note, err=True)
        click.echo(render_json([entry for block in blocks for entry in block.entries]))
    elif chosen == "markdown":
        click.echo(render_markdown(blocks, notes, titles))
    elif chosen == "table":
        print_table(blocks, notes, titles, primary)
    else:
        click.echo(render_text(blocks, notes, titles, primary))
