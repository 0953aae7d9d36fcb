"""The one exception type that reaches the user as a single clear line, and helpers that make one line
of other libraries' multi-line messages."""


class RostoolError(Exception):
    """A failure the user can act on: the message says what failed and what to do."""

    def __init__(self, message: str, exit_code: int = 1) -> None:
        super().__init__(message)
        self.exit_code = exit_code


def one_line(text: str, limit: int = 300) -> str:
    """`text` as a single line (messages of parsers and libraries often span several), cut at `limit`."""
    flat = " ".join(text.split())
    return flat if len(flat) <= limit else flat[: limit - 3] + "..."


def yaml_problem(err: Exception) -> str:
    """A YAML parser error in one line: what and where (PyYAML's own text spans several lines)."""
    problem = getattr(err, "problem", None) or getattr(err, "reason", None) or one_line(str(err))
    mark = getattr(err, "problem_mark", None)
    if mark is not None:
        return f"{problem} at line {mark.line + 1}, column {mark.column + 1}"
    position = getattr(err, "position", None)
    return f"{problem} at byte {position}" if position is not None else str(problem)
