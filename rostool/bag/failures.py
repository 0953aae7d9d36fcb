"""How a failure reads: a library's exception in one line, a damaged file's error naming the file, and the
`rostool: warning:` line of what goes on regardless."""

from __future__ import annotations

from contextlib import AbstractContextManager
from pathlib import Path
from types import TracebackType

from rostool.errors import RostoolError, one_line


def warn(text: str) -> None:
    """One `rostool: warning:` line on stderr: the command goes on."""
    import click

    click.echo(f"rostool: warning: {one_line(text, 500)}", err=True)


def describe(err: BaseException) -> str:
    """An exception of a library in one line (YAML and zstd errors span several)."""
    text = str(err.args[0]) if err.args and isinstance(err.args[0], str) else str(err)
    text = one_line(text)
    if isinstance(err, MemoryError):
        return "a length field claims more memory than there is (corrupt file?)"
    if isinstance(err, RecursionError):
        return "nesting too deep (corrupt file?)"
    if isinstance(err, OverflowError):
        return f"a length or offset field is out of range (corrupt file?): {text}"
    if not text:
        return type(err).__name__
    if isinstance(err, LookupError) or len(text) <= 3:
        return f"{type(err).__name__}: {text}"
    return text


class guard(AbstractContextManager["guard"]):
    """Turns any failure of the underlying readers on a damaged file into one RostoolError line."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc is None or not isinstance(exc, Exception):
            return
        if isinstance(exc, (RostoolError, BrokenPipeError)):
            return
        text = describe(exc)
        if "not indexed" in text:
            raise RostoolError(
                f"{self.path}: bag is not indexed (its recorder was killed?); run `rostool bag reindex`"
            ) from exc
        cut_short = ("magic", "damaged", "end of file", "Header could not")
        reindexable = self.path.is_file() and self.path.suffix != ".db3"  # reindex knows .bag and .mcap
        if reindexable and any(word in text for word in cut_short):
            text += "; if the file was cut short, `rostool bag reindex` can rebuild it"
        raise RostoolError(f"{self.path}: cannot read bag: {text}") from exc
