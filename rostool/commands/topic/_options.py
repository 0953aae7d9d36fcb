"""Options several topic verbs share."""

from __future__ import annotations

import click

include_hidden_option = click.option(
    "-a", "--include-hidden-topics", "--all", "include_hidden", is_flag=True,
    help="ROS 2: also hidden topics (a name part starting with _).",
)  # fmt: skip
