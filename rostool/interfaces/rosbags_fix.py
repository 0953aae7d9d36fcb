"""Work around a rosbags code-generation gap; import this before registering types at run time.

rosbags' generated message classes import ClassVar only under TYPE_CHECKING, so in types registered at
run time (every ROS 1 wire or bag type, every stored definition) dataclasses take constants such as
rosgraph_msgs/Log's DEBUG for fields, and echo would print them. Importing it for real fixes that.
"""

from __future__ import annotations

from typing import Any

import rosbags.typesys.store as _rosbags_store


def _generate_with_classvar(typs: Any) -> str:
    code: str = _original_generate(typs)
    future = "from __future__ import annotations\n"
    return code.replace(future, future + "from typing import ClassVar  # noqa: F401\n", 1)


_original_generate = _rosbags_store.generate_python_code
if getattr(_original_generate, "__name__", "") != "_generate_with_classvar":
    _rosbags_store.generate_python_code = _generate_with_classvar  # type: ignore[assignment]
