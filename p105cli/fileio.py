"""Writing files atomically: the one place that does temp file + fsync + rename.

The file at ``path`` is replaced only when the writer's block completes; on
any failure the temporary file is removed and an existing file is left as it
was. A new file gets the permissions the umask allows; a replaced file
keeps its own.
"""

from __future__ import annotations

import contextlib
import os


class AtomicWriteError(OSError):
    """The temporary file could not be created or renamed into place."""


def _default_mode(path: str) -> int:
    try:
        return os.stat(path).st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


@contextlib.contextmanager
def atomic_file(path, binary: bool = False):
    """Yield a file object (text: UTF-8 with ``\\n`` newlines) that becomes ``path`` on success.

    Failures of the mechanism itself (creating the temporary file, renaming it)
    raise AtomicWriteError; exceptions from the caller's block pass unchanged.
    """
    import tempfile  # here: it pulls in shutil, bz2, lzma and random, which most runs never need

    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(path)}.", suffix=".tmp", dir=directory)
    except OSError as err:
        raise AtomicWriteError(err.errno, err.strerror, path) from None
    try:
        with (open(fd, "wb") if binary else open(fd, "w", encoding="utf-8", newline="\n")) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, _default_mode(path))
        try:
            os.replace(tmp, path)
        except OSError as err:
            raise AtomicWriteError(err.errno, err.strerror, path) from None
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def write_text_atomically(path, text: str) -> None:
    """Replace ``path`` by ``text`` (UTF-8) atomically."""
    with atomic_file(path) as fh:
        fh.write(text)
