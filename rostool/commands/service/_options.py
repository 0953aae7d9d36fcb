"""Options several service verbs share."""

from __future__ import annotations

import click

hidden_services_option = click.option(
    "-a", "--include-hidden-services", "--all", "hidden", is_flag=True,
    help="ROS 2: also hidden services (a name part starting with _).",
)  # fmt: skip
count_option = click.option(
    "-c", "--count-services", "--count", "count", is_flag=True, help="Only the number of services."
)
