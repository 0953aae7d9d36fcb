"""Bags and outputs in object storage: `s3://bucket/prefix` and the other schemes pyarrow.fs knows.

A remote bag is copied into a temporary local directory when it is opened (the bag readers need files they
can seek in; rosbags and mcap read local files) and the copy is removed when the reader closes; a remote
output is written locally first and uploaded once complete, so a failed run leaves nothing half-written
there. Credentials and endpoints come from the usual variables (AWS_*, AWS_ENDPOINT_URL included) as
pyarrow.fs reads them, once, where the command starts: the resolved filesystem object travels with the work
(to Ray tasks too), so workers need no settings of their own.
"""

from __future__ import annotations

import os
import re
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

from rostool.bag.formats import FILE_SUFFIXES
from rostool.bag.rosbag2_metadata import METADATA
from rostool.errors import RostoolError

_URI = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*://")


def is_remote(text: object) -> bool:
    if isinstance(text, RemotePath):
        return True
    return isinstance(text, str) and bool(_URI.match(text)) and not text.startswith("file://")


@dataclass(frozen=True)
class RemotePath:
    """A file or a prefix in object storage, with the filesystem that reaches it."""

    uri: str
    filesystem: Any  # pyarrow.fs.FileSystem: picklable, settings included
    path: str  # the path inside `filesystem`: bucket/key

    @property
    def name(self) -> str:
        return PurePosixPath(self.path.rstrip("/")).name

    def child(self, relative: str) -> RemotePath:
        return RemotePath(
            f"{self.uri.rstrip('/')}/{relative}", self.filesystem, f"{self.path.rstrip('/')}/{relative}"
        )

    def __str__(self) -> str:
        return self.uri


def resolve(uri: str | RemotePath) -> RemotePath:
    if isinstance(uri, RemotePath):
        return uri
    try:
        import pyarrow.fs as pafs
    except ImportError as err:
        raise RostoolError(
            f"{uri}: object storage needs the pyarrow module: pip install 'rostool[export]'"
        ) from err
    try:
        filesystem, path = pafs.FileSystem.from_uri(uri)
    except (ValueError, OSError) as err:  # pyarrow's ArrowInvalid is a ValueError
        raise RostoolError(f"{uri}: cannot reach it: {_first_line(err)}") from err
    return RemotePath(uri, _with_credentials(filesystem), path)


def _with_credentials(filesystem: Any) -> Any:
    """An S3 filesystem carries the endpoint it was resolved with but not keys from the environment: put
    them in, so that a Ray worker without AWS settings (or with other ones) reaches the same storage as
    the command, and never falls back to its own credential chain."""
    import pyarrow.fs as pafs

    key, secret = os.environ.get("AWS_ACCESS_KEY_ID"), os.environ.get("AWS_SECRET_ACCESS_KEY")
    if not isinstance(filesystem, pafs.S3FileSystem) or not key or not secret:
        return filesystem
    settings = dict(filesystem.__reduce__()[1][0])
    settings.update(access_key=key, secret_key=secret, session_token=os.environ.get("AWS_SESSION_TOKEN"))
    proxy = settings.pop("proxy_options", None)
    if proxy and proxy.get("host"):
        settings["proxy_options"] = proxy
    return pafs.S3FileSystem(**{k: v for k, v in settings.items() if v is not None})


def _kind(remote: RemotePath) -> Any:
    import pyarrow.fs as pafs

    try:
        info = remote.filesystem.get_file_info(remote.path)
    except OSError as err:
        raise RostoolError(f"{remote}: cannot read: {_first_line(err)}") from err
    if info.type == pafs.FileType.NotFound:
        raise RostoolError(f"{remote}: no such file or prefix")
    return info.type


def _entries(remote: RemotePath, recursive: bool) -> list[Any]:
    import pyarrow.fs as pafs

    try:
        return list(remote.filesystem.get_file_info(pafs.FileSelector(remote.path, recursive=recursive)))
    except OSError as err:
        raise RostoolError(f"{remote}: cannot list: {_first_line(err)}") from err


def list_bags(remote: RemotePath) -> list[RemotePath]:
    """The bags under `remote`: itself when it is a bag file or a rosbag2 prefix (metadata.yaml), else its
    .bag/.mcap/.db3 files and rosbag2 prefixes, sorted."""
    import pyarrow.fs as pafs

    if _kind(remote) == pafs.FileType.File:
        return [remote]
    entries = _entries(remote, recursive=True)
    base = remote.path.rstrip("/") + "/"
    files = sorted(e.path[len(base) :] for e in entries if e.type == pafs.FileType.File)
    if METADATA in files:
        return [remote]
    rosbag2 = sorted({str(PurePosixPath(f).parent) for f in files if PurePosixPath(f).name == METADATA})
    bags = [remote.child(d) for d in rosbag2]
    for relative in files:
        inside = any(relative.startswith(d + "/") for d in rosbag2)
        if not inside and PurePosixPath(relative).suffix in FILE_SUFFIXES:
            bags.append(remote.child(relative))
    if not bags:
        raise RostoolError(f"{remote}: no bags under this prefix (.bag, .mcap, .db3 or rosbag2 prefixes)")
    return sorted(bags, key=lambda bag: bag.path)


@contextmanager
def local_copy(remote: RemotePath) -> Iterator[Path]:
    """The bag at `remote` (a file or a rosbag2 prefix) as a local path, for as long as the context lasts."""
    import pyarrow.fs as pafs

    kind = _kind(remote)
    with tempfile.TemporaryDirectory(prefix="rostool-remote-") as tmp:
        target = Path(tmp) / (remote.name or "bag")
        try:
            if kind == pafs.FileType.File:
                pafs.copy_files(remote.path, str(target), remote.filesystem, pafs.LocalFileSystem())
            else:
                target.mkdir()
                for entry in _entries(remote, recursive=False):
                    if entry.type == pafs.FileType.File:
                        local = str(target / PurePosixPath(entry.path).name)
                        pafs.copy_files(entry.path, local, remote.filesystem, pafs.LocalFileSystem())
        except OSError as err:
            raise RostoolError(f"{remote}: cannot download: {_first_line(err)}") from err
        yield target


def upload(local: Path, remote: RemotePath) -> list[str]:
    """Every file under `local`, to the same relative places under `remote`; their URIs."""
    import pyarrow.fs as pafs

    uploaded = []
    for path in sorted(p for p in local.rglob("*") if p.is_file()):
        relative = path.relative_to(local).as_posix()
        target = remote.child(relative)
        try:
            pafs.copy_files(str(path), target.path, pafs.LocalFileSystem(), remote.filesystem)
        except OSError as err:
            raise RostoolError(f"{target}: cannot upload: {_first_line(err)}") from err
        uploaded.append(target.uri)
    return uploaded


def _first_line(err: BaseException) -> str:
    text = str(err).strip() or type(err).__name__
    return text.splitlines()[0]
