"""The one exception type that reaches the user as a single clear line."""


class RostoolError(Exception):
    """A failure the user can act on: the message says what failed and what to do."""

    def __init__(self, message: str, exit_code: int = 1) -> None:
        super().__init__(message)
        self.exit_code = exit_code
