"""Writing files atomically: the one place that does temp file + fsync + rename.

The file at ``path`` is replaced only when the writer's block completes (or,
with :class:`PendingFile`, when its owner commits it); on any failure the
temporary file is removed and an existing file is left as it was. A new file
gets the permissions the umask allows; a replaced file keeps its own.

The temporary file lies next to ``path`` (a rename is atomic only within one
file system) under a name that says whose it is:
``.NAME.p105-HOST-PID-XXXXXXXX.tmp``. A process killed outright (``kill -9``,
the machine losing power) cannot remove it, so every write to ``path`` first
removes the temporaries of ``path`` left by p105 processes of this host that
no longer run.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re

#: Marks p105's temporary files among other hidden files of a directory.
TEMP_MARK = ".p105-"

#: errno values of a device that refuses the data (a full disk, a quota, a file size limit):
#: the environment's failure, reported with the path (exit 2), not a bug.
DEVICE_ERRNOS = frozenset(getattr(errno, name) for name in ("ENOSPC", "EDQUOT", "EFBIG", "EIO", "EROFS")
                          if hasattr(errno, name))


class AtomicWriteError(OSError):
    """The temporary file could not be created or renamed into place."""


def _default_mode(path: str) -> int:
    try:
        return os.stat(path).st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def _host() -> str:
    # In the name so that on a shared (network) directory only this host's dead processes are judged.
    import socket  # only when a file is written

    return re.sub(r"[^A-Za-z0-9]", "", socket.gethostname())[:24] or "host"


def _temp_prefix(path: str) -> str:
    # The target's name shortened: the temporary's name must stay within NAME_MAX (255).
    return f".{os.path.basename(path)[:120]}{TEMP_MARK}{_host()}-"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    except OSError:
        return True
    return True


def remove_stale_temporaries(path) -> list[str]:
    """Remove the temporaries of ``path`` that p105 processes of this host left when killed.

    A temporary belongs to a dead process when the process id in its name no
    longer runs; the temporaries of running processes (another p105 writing
    the same file) are left alone. Returns the paths removed.
    """
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    prefix = _temp_prefix(path)
    removed = []
    try:
        names = os.listdir(directory)
    except OSError:
        return removed
    for name in names:
        if not (name.startswith(prefix) and name.endswith(".tmp")):
            continue
        pid = name[len(prefix):].split("-", 1)[0]
        if not pid.isdigit() or int(pid) == os.getpid() or _alive(int(pid)):
            continue
        with contextlib.suppress(OSError):
            os.unlink(os.path.join(directory, name))
            removed.append(os.path.join(directory, name))
    return removed


class PendingFile:
    """A temporary file next to ``path`` that becomes ``path`` on :meth:`commit`.

    ``file`` is the stream to write (text: UTF-8 with ``\\n`` newlines).
    :meth:`finish` makes the data durable (flush, fsync, close): write errors
    such as a full disk surface there, as OSError. :meth:`commit` then renames
    it into place; :meth:`discard` removes it and leaves ``path`` as it was.
    """

    def __init__(self, path, binary: bool = False):
        self.path = os.fspath(path)
        remove_stale_temporaries(self.path)
        directory = os.path.dirname(os.path.abspath(self.path))
        try:
            import tempfile  # here: it pulls in shutil, bz2, lzma and random, which most runs never need

            fd, self.temp = tempfile.mkstemp(prefix=f"{_temp_prefix(self.path)}{os.getpid()}-", suffix=".tmp",
                                             dir=directory)
        except OSError as err:
            raise AtomicWriteError(err.errno, err.strerror, self.path) from None
        self.file = open(fd, "wb") if binary else open(fd, "w", encoding="utf-8", newline="\n")

    def finish(self) -> None:
        if not self.file.closed:
            self.file.flush()
            os.fsync(self.file.fileno())
            self.file.close()

    def commit(self) -> None:
        try:
            self.finish()
            os.chmod(self.temp, _default_mode(self.path))
            try:
                os.replace(self.temp, self.path)
            except OSError as err:
                raise AtomicWriteError(err.errno, err.strerror, self.path) from None
        except BaseException:
            self.discard()
            raise

    def discard(self) -> None:
        with contextlib.suppress(OSError, ValueError):
            self.file.close()  # may fail again (a full disk): the file is removed all the same
        with contextlib.suppress(OSError):
            os.unlink(self.temp)


@contextlib.contextmanager
def atomic_file(path, binary: bool = False):
    """Yield a file object (text: UTF-8 with ``\\n`` newlines) that becomes ``path`` on success.

    Failures of the mechanism itself (creating the temporary file, renaming it)
    raise AtomicWriteError; exceptions from the caller's block and write errors
    (OSError) pass unchanged.
    """
    pending = PendingFile(path, binary)
    try:
        yield pending.file
        pending.finish()
    except BaseException as err:
        pending.discard()
        if isinstance(err, OSError) and err.filename is None and err.errno in DEVICE_ERRNOS:
            raise OSError(err.errno, err.strerror, pending.path) from None  # (a full disk: say which file)
        raise
    pending.commit()


def write_text_atomically(path, text: str) -> None:
    """Replace ``path`` by ``text`` (UTF-8) atomically."""
    with atomic_file(path) as fh:
        fh.write(text)
